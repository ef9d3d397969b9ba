// The C++ reference driver of the jewelry-box scenario (scenario.h), and the C-call overhead benchmark.
//
//   cpp_reference <hash_out>                 runs the scenario through the C++ API, writes its state_hash
//   cpp_reference <hash_out> --bench <reps>  also times the same frames through the C ABI and the C++ API
//
// The executable links the core (C++ API) and libhandsim (C ABI) side by side: libhandsim exports only handsim_*
// (bindings/c/handsim.map), so its private copy of the core cannot clash with the one linked here.
#include "handsim.h"
#include "handsim/scenes.h"
#include "handsim/world.h"

#include "scenario.h"

#include <algorithm>
#include <chrono>
#include <cinttypes>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <string>
#include <vector>

namespace {

using namespace handsim;
using Clock = std::chrono::steady_clock;

struct Run {
  uint64_t hash = 0;
  double step_seconds = 0;  // sum over the frames of the step call alone
};

Run run_cpp() {
  Run r;
  World world;
  const JewelryBox box = build_jewelry_box(world);
  world.add_hand(HandDef{});
  const HandPoseParams shape = lid_pinch_shape();
  std::vector<HandFrame> frames(1);
  for (int i = 0; i < SCENARIO_FRAMES; ++i) {
    frames[0] = make_hand_frame(Handedness::Right, box.lid_pinch_palm(world, Handedness::Right, scenario_angle(i)),
                                shape);
    const auto t0 = Clock::now();
    world.step(SCENARIO_DT, frames);
    r.step_seconds += std::chrono::duration<double>(Clock::now() - t0).count();
  }
  r.hash = world.state_hash();
  return r;
}

void must(int status, const char* call) {
  if (status == HANDSIM_OK) return;
  std::fprintf(stderr, "%s returned %s: %s\n", call, handsim_status_name(status), handsim_last_error());
  std::exit(1);
}
#define MUST(call) must((call), #call)

Run run_c_abi() {
  Run r;
  handsim_world* world = nullptr;
  handsim_jewelry_box box;
  handsim_hand_id hand = 0;
  handsim_hand_pose_params shape;
  handsim_joint_pose joints[HANDSIM_HAND_JOINT_COUNT];
  MUST(handsim_world_create(nullptr, &world));
  MUST(handsim_build_jewelry_box(world, nullptr, &box));
  MUST(handsim_add_hand(world, nullptr, &hand));
  MUST(handsim_lid_pinch_shape(&shape));
  const handsim_hand_frame frame{HANDSIM_RIGHT, HANDSIM_HAND_JOINT_COUNT, joints};
  for (int i = 0; i < SCENARIO_FRAMES; ++i) {
    handsim_pose palm;
    MUST(handsim_jewelry_box_lid_pinch_palm(world, &box, HANDSIM_RIGHT, scenario_angle(i), 0.0, &palm));
    MUST(handsim_make_hand_frame(HANDSIM_RIGHT, &palm, &shape, joints, HANDSIM_HAND_JOINT_COUNT));
    const auto t0 = Clock::now();
    MUST(handsim_step(world, SCENARIO_DT, &frame, 1));
    r.step_seconds += std::chrono::duration<double>(Clock::now() - t0).count();
  }
  MUST(handsim_state_hash(world, &r.hash));
  MUST(handsim_world_destroy(world));
  return r;
}

// Seconds per call of a cheap query, the C++ method against its C function (min over `reps` batches).
template <class F>
double per_call(int reps, int calls, F&& call) {
  double best = 1e9;
  for (int rep = 0; rep < reps; ++rep) {
    const auto t0 = Clock::now();
    for (int i = 0; i < calls; ++i) call();
    best = std::min(best, std::chrono::duration<double>(Clock::now() - t0).count() / calls);
  }
  return best;
}

void bench(int reps) {
  double cpp_best = 1e9, c_best = 1e9;
  for (int rep = 0; rep < reps; ++rep) {
    cpp_best = std::min(cpp_best, run_cpp().step_seconds);
    c_best = std::min(c_best, run_c_abi().step_seconds);
  }
  std::printf("scenario step, min over %d runs of %d frames: C++ %.2f us/step, C ABI %.2f us/step "
              "(difference %+.2f us/step, %+.2f%%)\n",
              reps, SCENARIO_FRAMES, 1e6 * cpp_best / SCENARIO_FRAMES, 1e6 * c_best / SCENARIO_FRAMES,
              1e6 * (c_best - cpp_best) / SCENARIO_FRAMES, 100 * (c_best - cpp_best) / cpp_best);

  // A cheap query: World::body_pose against handsim_body_pose (same world contents, 1e6 calls per batch).
  World world;
  const JewelryBox box = build_jewelry_box(world);
  handsim_world* cworld = nullptr;
  handsim_jewelry_box cbox;
  MUST(handsim_world_create(nullptr, &cworld));
  MUST(handsim_build_jewelry_box(cworld, nullptr, &cbox));
  volatile double sink = 0;
  const int calls = 1000000;
  const double direct = per_call(reps, calls, [&] { sink = sink + world.body_pose(box.lid).position.y(); });
  const double via_c = per_call(reps, calls, [&] {
    handsim_pose p;
    handsim_body_pose(cworld, cbox.lid, &p);
    sink = sink + p.position.y;
  });
  std::printf("body pose query, min over %d batches of %d calls: C++ %.1f ns/call, C ABI %.1f ns/call\n", reps,
              calls, 1e9 * direct, 1e9 * via_c);
  MUST(handsim_world_destroy(cworld));
}

}  // namespace

int main(int argc, char** argv) {
  if (argc != 2 && !(argc == 4 && std::strcmp(argv[2], "--bench") == 0)) {
    std::fprintf(stderr, "usage: %s <hash_out> [--bench <reps>]\n", argv[0]);
    return 2;
  }
  const Run cpp = run_cpp(), c = run_c_abi();
  std::printf("jewelry box: state_hash C++ 0x%016" PRIx64 ", C ABI in the same process 0x%016" PRIx64 "\n", cpp.hash,
              c.hash);
  if (FILE* f = std::fopen(argv[1], "w")) {
    std::fprintf(f, "0x%016" PRIx64 "\n", cpp.hash);
    std::fclose(f);
  } else {
    std::fprintf(stderr, "cannot write %s\n", argv[1]);
    return 1;
  }
  if (cpp.hash != c.hash) {
    std::fprintf(stderr, "FAIL: the C ABI and the C++ API disagree\n");
    return 1;
  }
  if (argc == 4) bench(std::max(1, std::atoi(argv[3])));
  return 0;
}
