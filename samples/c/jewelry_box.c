/* A minimal C host: the paper's jewelry box, one right hand arriving open at the lid's lip, closing its pinch there
 * and swinging the lid open about the hinge over two seconds at 60 Hz; prints the lid angle every 10 frames. Only
 * handsim.h and libhandsim. */
#include "handsim.h"

#include <inttypes.h>
#include <stdio.h>

#define CHECK(call)                                                                                   \
  do {                                                                                                \
    int status_ = (call);                                                                             \
    if (status_ != HANDSIM_OK) {                                                                      \
      fprintf(stderr, "%s failed: %s: %s\n", #call, handsim_status_name(status_), handsim_last_error()); \
      return 1;                                                                                       \
    }                                                                                                 \
  } while (0)

int main(void) {
  const double pi = 3.14159265358979323846, dt = 1.0 / 60.0;
  handsim_world* world = NULL;
  handsim_jewelry_box box;
  handsim_hand_id hand;
  handsim_hand_pose_params pinch, shape;
  handsim_joint_pose joints[HANDSIM_HAND_JOINT_COUNT];
  handsim_hand_input input; /* the frame and the hand it drives */
  uint64_t hash = 0;
  int i;

  if (handsim_abi_version() >> 16 != HANDSIM_ABI_VERSION_MAJOR) {
    fprintf(stderr, "libhandsim ABI %08x does not match handsim.h %08x\n", (unsigned)handsim_abi_version(),
            (unsigned)HANDSIM_ABI_VERSION);
    return 1;
  }
  CHECK(handsim_world_create(NULL, &world));
  CHECK(handsim_build_jewelry_box(world, NULL, &box));
  CHECK(handsim_add_hand(world, NULL, &hand));
  CHECK(handsim_lid_pinch_shape(&pinch));
  input.hand = hand;
  input.frame.handedness = HANDSIM_RIGHT;
  input.frame.joint_count = HANDSIM_HAND_JOINT_COUNT;
  input.frame.joints = joints;

  printf("frame  time_s  hand_deg  lid_deg  grasped\n");
  for (i = 0; i <= 140; ++i) {
    /* The hand closes its pinch over 0.25 s as people do (the default grasp rule grasps only a closing hand), then
     * from frame 20 it swings to 80 degrees over 2 s. */
    const double t = i < 20 ? 0.0 : (i - 20) / 120.0;
    const double hand_angle = (t < 1.0 ? t : 1.0) * 80.0 * pi / 180.0;
    handsim_pose palm;
    handsim_joint_state hinge;
    handsim_grasp_info grasp;
    CHECK(handsim_closing_grip(&pinch, i * dt, 0.25, &shape));
    CHECK(handsim_jewelry_box_lid_pinch_palm(world, &box, HANDSIM_RIGHT, hand_angle, 0.0, &palm));
    CHECK(handsim_make_hand_frame(HANDSIM_RIGHT, &palm, &shape, joints, HANDSIM_HAND_JOINT_COUNT));
    CHECK(handsim_step_hands(world, dt, &input, 1));
    CHECK(handsim_get_joint_state(world, box.hinge, &hinge));
    CHECK(handsim_body_grasp(world, box.lid, &grasp));
    if (i % 10 == 0)
      printf("%5d  %6.3f  %8.2f  %7.2f  %s\n", i, (i + 1) * dt, hand_angle * 180.0 / pi, hinge.value * 180.0 / pi,
             grasp.grasped ? "yes" : "no");
  }
  CHECK(handsim_state_hash(world, &hash));
  printf("state_hash 0x%016" PRIx64 "\n", hash);
  CHECK(handsim_world_destroy(world));
  return 0;
}
