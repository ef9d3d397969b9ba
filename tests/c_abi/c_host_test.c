/* The C host test: a pure C99 program that uses libhandsim through handsim.h only.
 *
 *   c_host_test <hash_out> [<reference_hash_file>]
 *
 * Runs the jewelry-box scenario (the paper's Sec. IV box, one right hand pinching the lid's lip and swinging it
 * open over 2 s), checks the lid opens and stays on its hinge within [0, 90 deg], writes the final state_hash to
 * <hash_out> (the C# test and later the Python tests compare with it) and, given a reference file (the C++
 * driver's hash), checks they are equal. Then: bad inputs return the documented statuses and messages and
 * leave the world unchanged, every shape and joint type works through the ABI, and the struct layouts the C
 * compiler sees are the library's. Exit status 0 when every check passed. */
#include "handsim.h"

#include <inttypes.h>
#include <math.h>
#include <stddef.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "handsim/def_table.h"  /* the core's tables: preprocessor rows, valid C */
#include "handsim/enum_table.h"
#include "scenario.h"

static int g_checks = 0;
static int g_failures = 0;

#define CHECK(cond, ...)                                                   \
  do {                                                                     \
    ++g_checks;                                                            \
    if (!(cond)) {                                                         \
      ++g_failures;                                                        \
      fprintf(stderr, "FAIL %s:%d: %s: ", __FILE__, __LINE__, #cond);      \
      fprintf(stderr, __VA_ARGS__);                                        \
      fputc('\n', stderr);                                                 \
    }                                                                      \
  } while (0)

/* A call that must succeed; on failure the test stops (the rest would only cascade). */
#define MUST(call)                                                                                 \
  do {                                                                                             \
    int status_ = (call);                                                                          \
    if (status_ != HANDSIM_OK) {                                                                   \
      fprintf(stderr, "FAIL %s:%d: %s returned %s: %s\n", __FILE__, __LINE__, #call,              \
              handsim_status_name(status_), handsim_last_error());                                 \
      exit(1);                                                                                     \
    }                                                                                              \
  } while (0)

/* A call that must be rejected with `status` and a message starting with `prefix`, leaving `world`'s state
 * hash unchanged (world may be NULL for calls without one). */
#define REJECT(world, call, status, prefix) expect_rejected((world), (call), (status), (prefix), #call, __LINE__)

static uint64_t hash_of(const handsim_world* world) {
  uint64_t h = 0;
  MUST(handsim_state_hash(world, &h));
  return h;
}

static uint64_t g_hash_before;

static void expect_rejected(const handsim_world* world, int got, int status, const char* prefix, const char* call,
                            int line) {
  const char* message = handsim_last_error();
  ++g_checks;
  if (got != status || strncmp(message, prefix, strlen(prefix)) != 0) {
    ++g_failures;
    fprintf(stderr, "FAIL line %d: %s\n  returned %s \"%s\", expected %s \"%s...\"\n", line, call,
            handsim_status_name(got), message, handsim_status_name(status), prefix);
  } else {
    printf("  rejected as documented: %-16s %s\n", handsim_status_name(got), message);
  }
  if (world) CHECK(hash_of(world) == g_hash_before, "line %d: the world changed after a rejected call", line);
}

/* --- the scenario ----------------------------------------------------------------------------------------- */

/* Frame i of scenario.h's right hand: the lid pinch closing onto the lip, then swung with the lid. */
static void scenario_hand(const handsim_world* world, const handsim_jewelry_box* box, int i,
                          handsim_joint_pose* joints) {
  handsim_hand_pose_params pinch, shape;
  handsim_pose palm;
  MUST(handsim_lid_pinch_shape(&pinch));
  MUST(handsim_closing_grip(&pinch, scenario_grip_t(i), SCENARIO_CLOSING_S, &shape));
  MUST(handsim_jewelry_box_lid_pinch_palm(world, box, HANDSIM_RIGHT, scenario_angle(i), 0.0, &palm));
  MUST(handsim_make_hand_frame(HANDSIM_RIGHT, &palm, &shape, joints, HANDSIM_HAND_JOINT_COUNT));
}

typedef struct scenario_result {
  uint64_t hash;
  double max_angle, min_angle, final_angle, max_violation;
  int grasped_frames, grasp_begin_events;
} scenario_result;

static scenario_result run_scenario(void) {
  scenario_result r = {0, -1e9, 1e9, 0, 0, 0, 0};
  handsim_world* world = NULL;
  handsim_jewelry_box box;
  handsim_hand_id hand = 0;
  handsim_joint_pose joints[HANDSIM_HAND_JOINT_COUNT];
  handsim_hand_input input;
  handsim_event events[16];
  int i;
  MUST(handsim_world_create(NULL, &world));
  MUST(handsim_build_jewelry_box(world, NULL, &box));
  MUST(handsim_add_hand(world, NULL, &hand));
  input.hand = hand;
  input.frame.handedness = HANDSIM_RIGHT;
  input.frame.joint_count = HANDSIM_HAND_JOINT_COUNT;
  input.frame.joints = joints;
  for (i = 0; i < SCENARIO_FRAMES; ++i) {
    handsim_joint_state hinge;
    handsim_grasp_info grasp;
    int32_t n = 0, k;
    scenario_hand(world, &box, i, joints);
    MUST(handsim_step_hands(world, SCENARIO_DT, &input, 1));
    MUST(handsim_get_joint_state(world, box.hinge, &hinge));
    MUST(handsim_body_grasp(world, box.lid, &grasp));
    MUST(handsim_events(world, events, 16, &n));
    for (k = 0; k < n; ++k)
      if (events[k].type == HANDSIM_EVENT_GRASP_BEGIN && events[k].body == box.lid && events[k].hand == hand)
        ++r.grasp_begin_events;
    r.grasped_frames += grasp.grasped != 0;
    if (hinge.value > r.max_angle) r.max_angle = hinge.value;
    if (hinge.value < r.min_angle) r.min_angle = hinge.value;
    if (hinge.violation > r.max_violation) r.max_violation = hinge.violation;
    r.final_angle = hinge.value;
  }
  r.hash = hash_of(world);
  MUST(handsim_world_destroy(world));
  return r;
}

static void test_scenario(const char* hash_out, const char* reference) {
  const double deg = 3.14159265358979323846 / 180.0;
  scenario_result a = run_scenario(), b = run_scenario();
  FILE* f;
  printf("jewelry box: lid angle max %.4f deg, min %.4f deg, final %.4f deg; max violation %.3g m; grasped "
         "%d of %d frames\n",
         a.max_angle / deg, a.min_angle / deg, a.final_angle / deg, a.max_violation, a.grasped_frames,
         SCENARIO_FRAMES);
  printf("jewelry box: state_hash 0x%016" PRIx64 "\n", a.hash);
  CHECK(a.hash == b.hash, "two runs: 0x%016" PRIx64 " vs 0x%016" PRIx64, a.hash, b.hash);
  CHECK(a.max_angle > 60 * deg, "the lid opened only to %.2f deg", a.max_angle / deg);
  CHECK(a.min_angle >= 0.0 && a.max_angle <= 90 * deg + 1e-12, "lid left [0, 90] deg: %.6f..%.6f deg",
        a.min_angle / deg, a.max_angle / deg);
  CHECK(a.max_violation <= 1e-9, "hinge violation %.3g m", a.max_violation);
  CHECK(a.grasped_frames > SCENARIO_FRAMES / 2, "the lid was grasped in only %d frames", a.grasped_frames);
  CHECK(a.grasp_begin_events == 1, "%d grasp-begin events", a.grasp_begin_events);

  f = fopen(hash_out, "w");
  CHECK(f != NULL, "cannot write %s", hash_out);
  if (f) {
    fprintf(f, "0x%016" PRIx64 "\n", a.hash);
    fclose(f);
  }
  if (reference) {
    unsigned long long expected = 0;
    f = fopen(reference, "r");
    CHECK(f != NULL && fscanf(f, "%llx", &expected) == 1, "cannot read the reference hash %s", reference);
    if (f) fclose(f);
    CHECK(a.hash == (uint64_t)expected, "C ABI hash 0x%016" PRIx64 " != C++ reference 0x%016llx", a.hash, expected);
  }
}

/* --- a world with one of everything -------------------------------------------------------------------------- */

static handsim_body_id add_box(handsim_world* world, double mass, double x, double y, double z) {
  handsim_body_def def;
  handsim_body_id id = 0;
  MUST(handsim_body_def_default(&def));
  def.mass = mass;
  def.pose.position.x = x;
  def.pose.position.y = y;
  def.pose.position.z = z;
  MUST(handsim_add_body(world, &def, &id));
  return id;
}

static void test_shapes_and_joints(void) {
  static const handsim_vec3 hull[] = {{-0.05, -0.05, -0.05}, {0.05, -0.05, -0.05}, {0.0, 0.05, -0.05},
                                      {0.0, 0.0, 0.05}};
  static const handsim_vec3 ramp[] = {{-1, 0.2, -1}, {1, 0.2, -1}, {1, 0.2, 1}, {-1, 0.2, 1}};
  static const int32_t ramp_indices[] = {0, 1, 2, 0, 2, 3};
  handsim_world* world = NULL;
  handsim_world_settings settings;
  handsim_body_def def;
  handsim_body_id sphere, capsule, hull_body, mesh, anchor, door, drawer, pendulum, welded;
  handsim_joint_id hinge, slider, ball, fixed;
  handsim_hinge_def hd;
  handsim_slider_def sd;
  handsim_ball_def bd;
  handsim_fixed_def fd;
  handsim_joint_state js;
  handsim_body_info info;
  handsim_pose pose;
  handsim_vec3 lin, ang;
  handsim_body_id ids[16];
  handsim_pose poses[2];
  int32_t n = 0, alive = 0, i;
  double t = 0;

  MUST(handsim_world_settings_default(&settings));
  CHECK(settings.gravity.y == -9.81 && settings.fixed_substep == 1.0 / 240.0 && settings.ground == 1 &&
            settings.skin_depth == 0 && settings.skin_pressure == 20e3 && settings.push_model == HANDSIM_PUSH_WRAP,
        "the defaults are not the C++ ones");
  settings.solver_iterations = 20;
  MUST(handsim_world_create(&settings, &world));
  MUST(handsim_get_world_settings(world, &settings));
  CHECK(settings.solver_iterations == 20, "settings round trip: %d", (int)settings.solver_iterations);

  MUST(handsim_body_def_default(&def));
  def.shape.type = HANDSIM_SHAPE_SPHERE;
  def.shape.radius = 0.04;
  def.pose.position.y = 0.5;
  MUST(handsim_add_body(world, &def, &sphere));
  def.shape.type = HANDSIM_SHAPE_CAPSULE;
  def.shape.half_height = 0.05;
  def.pose.position.x = 0.5;
  MUST(handsim_add_body(world, &def, &capsule));
  def.shape.type = HANDSIM_SHAPE_CONVEX_HULL;
  def.shape.points = hull;
  def.shape.point_count = 4;
  def.pose.position.x = -0.5;
  MUST(handsim_add_body(world, &def, &hull_body));
  def.shape.type = HANDSIM_SHAPE_TRIANGLE_MESH;
  def.shape.points = ramp;
  def.shape.point_count = 4;
  def.shape.indices = ramp_indices;
  def.shape.index_count = 6;
  def.mass = 0;
  def.pose.position.x = 5;  /* away from the others */
  MUST(handsim_add_body(world, &def, &mesh));
  MUST(handsim_get_body_info(world, mesh, &info));
  CHECK(info.motion == HANDSIM_MOTION_STATIC && info.shape_type == HANDSIM_SHAPE_TRIANGLE_MESH &&
            info.point_count == 4 && info.index_count == 6, "mesh info");

  anchor = add_box(world, 0, 0, 1.5, 1);
  door = add_box(world, 1, 0.1, 1.5, 1);
  drawer = add_box(world, 1, 0, 1.5, 2);
  pendulum = add_box(world, 1, 0, 1.2, 3);
  welded = add_box(world, 1, 0.2, 1.5, 1);

  MUST(handsim_hinge_def_default(&hd));
  hd.parent = anchor;
  hd.child = door;
  hd.pivot_parent.x = 0.05;
  hd.pivot_child.x = -0.05;
  hd.axis_parent.x = 0; hd.axis_parent.y = 1;
  hd.axis_child.x = 0; hd.axis_child.y = 1;
  hd.lower = -1;
  hd.upper = 1;
  MUST(handsim_add_hinge(world, &hd, &hinge));
  MUST(handsim_slider_def_default(&sd));
  sd.parent = 0; /* the world */
  sd.child = drawer;
  sd.anchor_parent.y = 1.5; sd.anchor_parent.z = 2;
  sd.axis.x = 0; sd.axis.y = 1; /* vertical: it falls to its lower limit */
  sd.lower = -0.2;
  sd.upper = 0.2;
  MUST(handsim_add_slider(world, &sd, &slider));
  MUST(handsim_ball_def_default(&bd));
  bd.child = pendulum;
  bd.pivot_parent.y = 1.5; bd.pivot_parent.z = 3;
  bd.pivot_child.y = 0.3;
  bd.has_cone_limit = 1;
  bd.cone_axis.y = -1; bd.cone_axis.x = 0;
  bd.cone_half_angle = 0.5;
  MUST(handsim_add_ball(world, &bd, &ball));
  MUST(handsim_fixed_def_default(&fd));
  fd.parent = door;
  fd.child = welded;
  fd.relative.position.x = 0.1;
  MUST(handsim_add_fixed(world, &fd, &fixed));

  MUST(handsim_set_joint_value(world, hinge, 5.0));  /* clamped to the upper limit */
  MUST(handsim_get_joint_state(world, hinge, &js));
  CHECK(js.type == HANDSIM_JOINT_HINGE && js.value == 1.0 && js.parent == anchor && js.child == door,
        "hinge state after set_joint_value: value %g", js.value);
  MUST(handsim_joints(world, NULL, 0, &n));
  CHECK(n == 4, "%d joints", (int)n);

  for (i = 0; i < 120; ++i) MUST(handsim_step(world, 1.0 / 60.0, NULL, 0));
  MUST(handsim_world_time(world, &t));
  CHECK(fabs(t - 2.0) < 1e-12, "time %.17g", t);
  MUST(handsim_body_pose(world, sphere, &pose));
  CHECK(fabs(pose.position.y - 0.04) < 2e-3, "the sphere rests on the ground: y = %.6f", pose.position.y);
  MUST(handsim_body_velocity(world, sphere, &lin, &ang));
  CHECK(fabs(lin.y) < 0.05, "the sphere is at rest: vy = %.4f", lin.y);
  MUST(handsim_get_joint_state(world, slider, &js));
  CHECK(fabs(js.value + 0.2) < 1e-12 && js.violation <= 1e-9, "the drawer fell to its lower limit: %.6f", js.value);
  MUST(handsim_get_joint_state(world, ball, &js));
  CHECK(js.type == HANDSIM_JOINT_BALL && js.violation <= 1e-9, "ball violation %.3g", js.violation);
  MUST(handsim_get_joint_state(world, fixed, &js));
  CHECK(js.type == HANDSIM_JOINT_FIXED && js.violation <= 1e-9, "fixed violation %.3g", js.violation);

  ids[0] = door;
  ids[1] = welded;
  MUST(handsim_body_poses(world, ids, 2, poses));
  {
    const double dx = poses[1].position.x - poses[0].position.x, dy = poses[1].position.y - poses[0].position.y,
                 dz = poses[1].position.z - poses[0].position.z;
    CHECK(fabs(sqrt(dx * dx + dy * dy + dz * dz) - 0.1) < 1e-9, "the welded box stays 0.1 m from the door");
  }

  /* removal, stale ids and generations */
  REJECT(NULL, handsim_remove_body(world, door), HANDSIM_INVALID_STATE, "body: a joint still uses it");
  MUST(handsim_remove_joint(world, fixed));
  MUST(handsim_remove_body(world, welded));
  MUST(handsim_contains_body(world, welded, &alive));
  CHECK(alive == 0, "a removed body is not alive");
  welded = add_box(world, 1, 3, 1, 3);  /* reuses the slot with a new generation */
  MUST(handsim_contains_body(world, ids[1], &alive));
  CHECK(alive == 0 && (welded & 0xffffffffu) == (ids[1] & 0xffffffffu) && welded != ids[1],
        "slot reuse bumps the generation");
  MUST(handsim_bodies(world, ids, 16, &n));
  CHECK(n == 9, "%d bodies", (int)n);
  MUST(handsim_world_reset(world));
  MUST(handsim_bodies(world, NULL, 0, &n));
  CHECK(n == 0, "%d bodies after reset", (int)n);
  MUST(handsim_world_destroy(world));
  MUST(handsim_world_destroy(NULL));
}

/* --- hands: particles, render vertices, stage reports -------------------------------------------------------- */

static void test_hand_outputs(handsim_world* world, handsim_hand_id hand) {
  handsim_hand_info info;
  handsim_stage_report reports[16];
  handsim_vec3* particles;
  handsim_vec3* deformed;
  float* vertices;
  int32_t* triangles;
  int32_t n = 0, i, moved = 0;
  char summary[2048];

  MUST(handsim_get_hand_info(world, hand, &info));
  CHECK(info.tracked && info.handedness == HANDSIM_RIGHT && info.particle_count == 1182,
        "hand info: tracked %d, %d particles", (int)info.tracked, (int)info.particle_count);
  MUST(handsim_hand_particles(world, hand, 0, NULL, 0, &n));
  CHECK(n == info.particle_count, "particle size query %d", (int)n);
  particles = (handsim_vec3*)malloc(sizeof(handsim_vec3) * (size_t)n);
  deformed = (handsim_vec3*)malloc(sizeof(handsim_vec3) * (size_t)n);
  MUST(handsim_hand_particles(world, hand, 0, particles, n, &n));
  MUST(handsim_hand_particles(world, hand, 1, deformed, n, &n));
  for (i = 0; i < n; ++i)
    moved += particles[i].x != deformed[i].x || particles[i].y != deformed[i].y || particles[i].z != deformed[i].z;
  printf("hand: %d particles, %d deformed away from their tracked position\n", (int)n, (int)moved);
  CHECK(moved > 0, "the pinching fingers deform some particles");

  MUST(handsim_hand_render_vertices_f32(world, hand, NULL, 0, &n));
  CHECK(n == info.vertex_count && n > 1000, "render vertices %d", (int)n);
  vertices = (float*)malloc(sizeof(float) * 3 * (size_t)n);
  MUST(handsim_hand_render_vertices_f32(world, hand, vertices, n, &n));
  CHECK(isfinite(vertices[0]) && isfinite(vertices[3 * n - 1]), "finite render vertices");
  MUST(handsim_hand_triangles(world, hand, NULL, 0, &n));
  CHECK(n == info.triangle_index_count && n % 3 == 0, "triangle indices %d", (int)n);
  triangles = (int32_t*)malloc(sizeof(int32_t) * (size_t)n);
  MUST(handsim_hand_triangles(world, hand, triangles, n, &n));
  for (i = 0; i < n; ++i)
    if (triangles[i] < 0 || triangles[i] >= info.vertex_count) break;
  CHECK(i == n, "triangle index %d out of range", (int)i);

  MUST(handsim_stage_reports(world, reports, 16, &n));
  CHECK(n >= 9, "%d stage reports", (int)n);
  for (i = 0; i < n; ++i) printf("  stage %-12s %s %8.1f us\n", reports[i].name, reports[i].ran ? "ran " : "skip",
                                 reports[i].seconds * 1e6);
  CHECK(strcmp(reports[0].name, "skinning") == 0 && reports[0].ran, "first stage %s", reports[0].name);
  {
    handsim_step_report last;
    MUST(handsim_last_step(world, &last));
    CHECK(last.stages[HANDSIM_STAGE_SKINNING].stage == HANDSIM_STAGE_SKINNING &&
              last.stages[HANDSIM_STAGE_SKINNING].skip == HANDSIM_SKIP_NONE &&
              last.stages[HANDSIM_STAGE_SKINNING].work == 1 && last.stages[HANDSIM_STAGE_SKINNING].particles > 0,
          "last step: skinning skip %d work %d", (int)last.stages[0].skip, (int)last.stages[0].work);
  }
  MUST(handsim_stage_summary(world, NULL, 0, &n));
  CHECK(n > 1 && n <= (int32_t)sizeof summary, "summary length %d", (int)n);
  MUST(handsim_stage_summary(world, summary, (int32_t)sizeof summary, &n));
  CHECK(strstr(summary, "skinning") != NULL && (int32_t)strlen(summary) + 1 == n, "summary text");
  free(particles);
  free(deformed);
  free(vertices);
  free(triangles);
}

/* --- save and restore: a world restored from handsim_save_state's bytes continues bit for bit ------------- */

#define SAVE_AT 80         /* the lid is held, a third of the way up its swing */
#define CONTINUE_FOR 1000  /* frames compared after the save (the schedule holds the lid at its stop from 130) */

typedef struct pinch_world {
  handsim_world* world;
  handsim_jewelry_box box;
  handsim_joint_pose joints[HANDSIM_HAND_JOINT_COUNT];
  handsim_hand_input input;
} pinch_world;

static void pinch_world_create(pinch_world* p) {
  handsim_hand_id hand = 0;
  MUST(handsim_world_create(NULL, &p->world));
  MUST(handsim_build_jewelry_box(p->world, NULL, &p->box));
  MUST(handsim_add_hand(p->world, NULL, &hand));
  p->input.hand = hand;
  p->input.frame.handedness = HANDSIM_RIGHT;
  p->input.frame.joint_count = HANDSIM_HAND_JOINT_COUNT;
  p->input.frame.joints = p->joints;
}

static void pinch_world_step(pinch_world* p, int i) {
  scenario_hand(p->world, &p->box, i, p->joints);
  MUST(handsim_step_hands(p->world, SCENARIO_DT, &p->input, 1));
}

static void test_save_restore(void) {
  pinch_world a, b;
  uint8_t* bytes;
  uint64_t* expected = (uint64_t*)malloc(CONTINUE_FOR * sizeof(uint64_t));
  int32_t size = 0, written = 0;
  int i, first_difference = -1;
  handsim_grasp_info grasp;
  pinch_world_create(&a);
  for (i = 0; i < SAVE_AT; ++i) pinch_world_step(&a, i);
  MUST(handsim_body_grasp(a.world, a.box.lid, &grasp));
  CHECK(grasp.grasped, "the lid should be held at the save");
  g_hash_before = hash_of(a.world);
  MUST(handsim_save_state(a.world, NULL, 0, &size));
  CHECK(size > 40, "a state of %d bytes", (int)size);
  bytes = (uint8_t*)malloc((size_t)size);
  MUST(handsim_save_state(a.world, bytes, size, &written));
  CHECK(written == size, "size query %d, saved %d", (int)size, (int)written);
  CHECK(hash_of(a.world) == g_hash_before, "saving changed the state");
  for (i = 0; i < CONTINUE_FOR; ++i) {
    pinch_world_step(&a, SAVE_AT + i);
    expected[i] = hash_of(a.world);
  }

  pinch_world_create(&b);
  for (i = 0; i < 25; ++i) pinch_world_step(&b, i); /* a different past */
  MUST(handsim_restore_state(b.world, bytes, size));
  CHECK(hash_of(b.world) == g_hash_before, "restored hash differs from the saved world's");
  for (i = 0; i < CONTINUE_FOR && first_difference < 0; ++i) {
    pinch_world_step(&b, SAVE_AT + i);
    if (hash_of(b.world) != expected[i]) first_difference = i;
  }
  CHECK(first_difference < 0, "the restored world diverged %d frames after the restore", first_difference);
  printf("save/restore: %d bytes; the restored world matched the saving world's hash for %d frames\n", (int)size,
         first_difference < 0 ? CONTINUE_FOR : first_difference);

  /* Bad bytes: refused naming "state", the world unchanged. */
  g_hash_before = hash_of(b.world);
  REJECT(b.world, handsim_restore_state(b.world, bytes, size - 1), HANDSIM_INVALID_ARGUMENT, "state: is truncated");
  REJECT(b.world, handsim_restore_state(b.world, bytes, 12), HANDSIM_INVALID_ARGUMENT, "state: is 12 bytes");
  REJECT(b.world, handsim_restore_state(b.world, NULL, size), HANDSIM_INVALID_ARGUMENT, "state: must not be null");
  REJECT(b.world, handsim_restore_state(b.world, bytes, -1), HANDSIM_INVALID_ARGUMENT, "size: must be >= 0");
  bytes[8] = 7; /* the format version */
  REJECT(b.world, handsim_restore_state(b.world, bytes, size), HANDSIM_INVALID_ARGUMENT, "state: has format version 7");
  bytes[8] = 1;
  bytes[size / 2] ^= 1;
  REJECT(b.world, handsim_restore_state(b.world, bytes, size), HANDSIM_INVALID_ARGUMENT, "state: is corrupt");
  bytes[size / 2] ^= 1;
  {
    handsim_body_def extra;
    handsim_body_id id = 0;
    MUST(handsim_body_def_default(&extra));
    MUST(handsim_add_body(b.world, &extra, &id));
    g_hash_before = hash_of(b.world);
    REJECT(b.world, handsim_restore_state(b.world, bytes, size), HANDSIM_INVALID_ARGUMENT,
           "state: was saved from a world with other");
  }
  free(bytes);
  free(expected);
  MUST(handsim_world_destroy(a.world));
  MUST(handsim_world_destroy(b.world));
}

/* --- bad inputs: documented statuses and messages, and the world is unchanged --------------------------------- */

/* --- the step report: skip reasons and warnings -------------------------------------------------------------- */

static void test_step_report(void) {
  handsim_world* world = NULL;
  handsim_step_report r;
  handsim_body_def def;
  handsim_body_id body;
  MUST(handsim_world_create(NULL, &world));
  MUST(handsim_last_step(world, &r));
  CHECK(r.substeps == 0 && r.warnings == 0, "before the first step: %d substeps", (int)r.substeps);
  MUST(handsim_body_def_default(&def));
  def.pose.position.y = 1;
  MUST(handsim_add_body(world, &def, &body));
  MUST(handsim_step(world, 1.0 / 60, NULL, 0));
  MUST(handsim_last_step(world, &r));
  CHECK(r.stages[HANDSIM_STAGE_SKINNING].skip == HANDSIM_SKIP_NO_TRACKED_HAND &&
            r.stages[HANDSIM_STAGE_JOINTS].skip == HANDSIM_SKIP_NO_JOINTS &&
            r.stages[HANDSIM_STAGE_DYNAMICS].skip == HANDSIM_SKIP_NONE && r.substeps == 4 && r.warnings == 0,
        "no hand: skinning skip %d, joints skip %d, %d substeps", (int)r.stages[0].skip, (int)r.stages[7].skip,
        (int)r.substeps);
  MUST(handsim_step(world, 1.0, NULL, 0)); /* 240 substeps owed, 8 run */
  MUST(handsim_last_step(world, &r));
  CHECK((r.warnings & (1u << HANDSIM_WARNING_SUBSTEPS_DROPPED)) && r.substeps == 8 &&
            fabs(r.dropped_seconds - (1.0 - 8.0 / 240)) < 1e-12,
        "huge dt: warnings %u, %d substeps, %g s dropped", (unsigned)r.warnings, (int)r.substeps, r.dropped_seconds);
  REJECT(NULL, handsim_last_step(world, NULL), HANDSIM_INVALID_ARGUMENT, "out_report: must not be null");
  MUST(handsim_world_destroy(world));
}

/* --- hands addressed by id: after remove_hand(a); add_hand(c), c takes a's slot; a frame for b drives b ----- */

static int32_t tracked(const handsim_world* world, handsim_hand_id hand) {
  handsim_hand_info info;
  MUST(handsim_get_hand_info(world, hand, &info));
  return info.tracked;
}

static void test_hands_by_id(void) {
  handsim_world* world = NULL;
  handsim_hand_id a = 0, b = 0, c = 0;
  handsim_joint_pose joints[HANDSIM_HAND_JOINT_COUNT];
  handsim_pose palm = {{0.3, 0.5, -0.2}, {0, 0, 0, 1}};
  handsim_hand_input inputs[2];
  MUST(handsim_world_create(NULL, &world));
  MUST(handsim_add_hand(world, NULL, &a));
  MUST(handsim_add_hand(world, NULL, &b));
  MUST(handsim_remove_hand(world, a));
  MUST(handsim_add_hand(world, NULL, &c));
  CHECK((c & 0xffffffffu) == (a & 0xffffffffu), "c reuses a's slot");
  MUST(handsim_make_hand_frame(HANDSIM_RIGHT, &palm, NULL, joints, HANDSIM_HAND_JOINT_COUNT));
  inputs[0].hand = b;
  inputs[0].frame.handedness = HANDSIM_RIGHT;
  inputs[0].frame.joint_count = HANDSIM_HAND_JOINT_COUNT;
  inputs[0].frame.joints = joints;
  MUST(handsim_step_hands(world, SCENARIO_DT, inputs, 1));
  CHECK(tracked(world, b) && !tracked(world, c), "the frame for b drives b, c has none");
  g_hash_before = hash_of(world);
  inputs[1] = inputs[0];
  REJECT(world, handsim_step_hands(world, SCENARIO_DT, inputs, 2), HANDSIM_INVALID_ARGUMENT, "hands[1].hand: index ");
  inputs[1].hand = a;
  REJECT(world, handsim_step_hands(world, SCENARIO_DT, inputs, 2), HANDSIM_STALE_ID, "hands[1].hand: names no live");
  CHECK(tracked(world, b) && !tracked(world, c), "a refused step changes nothing");
  MUST(handsim_world_destroy(world));
}

static void test_bad_inputs(void) {
  handsim_world* world = NULL;
  handsim_world* other = NULL;
  handsim_world_settings settings;
  handsim_jewelry_box box;
  handsim_hand_id hand = 0;
  handsim_hand_pose_params shape;
  handsim_joint_pose joints[HANDSIM_HAND_JOINT_COUNT];
  handsim_hand_frame frames[2];
  handsim_hand_input inputs[2];
  handsim_hand_id removed_hand = 0;
  handsim_body_def def;
  handsim_hinge_def hd;
  handsim_ball_def bd;
  handsim_pose palm, pose;
  handsim_vec3 small[10];
  handsim_body_id stale = 0, foreign = 0, id = 0;
  handsim_layout_entry entry;
  uint64_t fake_world[8] = {0};
  int32_t n = -1, i;

  MUST(handsim_world_create(NULL, &world));
  MUST(handsim_build_jewelry_box(world, NULL, &box));
  MUST(handsim_add_hand(world, NULL, &hand));
  MUST(handsim_lid_pinch_shape(&shape));
  frames[0].handedness = HANDSIM_RIGHT;
  frames[0].joint_count = HANDSIM_HAND_JOINT_COUNT;
  frames[0].joints = joints;
  frames[1] = frames[0];
  for (i = 0; i < SCENARIO_SWING_FROM; ++i) {
    scenario_hand(world, &box, i, joints);
    MUST(handsim_step(world, SCENARIO_DT, frames, 1));
  }
  MUST(handsim_jewelry_box_lid_pinch_palm(world, &box, HANDSIM_RIGHT, 0.0, 0.0, &palm));
  test_hand_outputs(world, hand);
  stale = add_box(world, 1, 2, 0.5, 2);
  MUST(handsim_remove_body(world, stale));
  MUST(handsim_add_hand(world, NULL, &removed_hand));
  MUST(handsim_remove_hand(world, removed_hand));
  MUST(handsim_world_create(NULL, &other));
  foreign = add_box(other, 1, 0, 0.5, 0);
  g_hash_before = hash_of(world);
  printf("bad inputs:\n");

  /* the step */
  REJECT(world, handsim_step(world, NAN, frames, 1), HANDSIM_INVALID_ARGUMENT, "dt: must be finite and > 0");
  REJECT(world, handsim_step(world, -1.0 / 60.0, frames, 1), HANDSIM_INVALID_ARGUMENT, "dt:");
  REJECT(world, handsim_step(world, INFINITY, frames, 1), HANDSIM_INVALID_ARGUMENT, "dt:");
  REJECT(world, handsim_step(world, SCENARIO_DT, NULL, 1), HANDSIM_INVALID_ARGUMENT, "hands: must not be null");
  REJECT(world, handsim_step(world, SCENARIO_DT, frames, -1), HANDSIM_INVALID_ARGUMENT, "hand_count: must be >= 0");
  REJECT(world, handsim_step(world, SCENARIO_DT, frames, 2), HANDSIM_INVALID_ARGUMENT,
         "hands: got 2 frames but the world has 1 hands");
  frames[0].joint_count = 25;
  REJECT(world, handsim_step(world, SCENARIO_DT, frames, 1), HANDSIM_INVALID_ARGUMENT,
         "hands[0].joint_count: must be 26");
  frames[0].joint_count = HANDSIM_HAND_JOINT_COUNT;
  frames[0].joints = NULL;
  REJECT(world, handsim_step(world, SCENARIO_DT, frames, 1), HANDSIM_INVALID_ARGUMENT, "hands[0].joints: must not be null");
  frames[0].joints = joints;
  frames[0].handedness = HANDSIM_LEFT;
  REJECT(world, handsim_step(world, SCENARIO_DT, frames, 1), HANDSIM_INVALID_ARGUMENT,
         "hands[0].handedness: does not match");
  frames[0].handedness = 7;
  REJECT(world, handsim_step(world, SCENARIO_DT, frames, 1), HANDSIM_INVALID_ARGUMENT,
         "hands[0].handedness: must be Left or Right");
  frames[0].handedness = HANDSIM_RIGHT;
  joints[7].orientation.w = 0.5;
  REJECT(world, handsim_step(world, SCENARIO_DT, frames, 1), HANDSIM_INVALID_ARGUMENT,
         "hands[0].joints[7].orientation: quaternion (x,y,z,w) must have unit length");
  joints[7].valid = 0; /* an invalid joint may hold anything */
  joints[7].position.x = NAN;
  MUST(handsim_make_hand_frame(HANDSIM_RIGHT, &palm, &shape, joints, HANDSIM_HAND_JOINT_COUNT));
  /* the step by id: ids are checked first, then each frame */
  inputs[0].hand = hand;
  inputs[0].frame = frames[0];
  inputs[1] = inputs[0];
  REJECT(world, handsim_step_hands(world, NAN, inputs, 1), HANDSIM_INVALID_ARGUMENT, "dt: must be finite and > 0");
  REJECT(world, handsim_step_hands(world, SCENARIO_DT, NULL, 1), HANDSIM_INVALID_ARGUMENT, "hands: must not be null");
  REJECT(world, handsim_step_hands(world, SCENARIO_DT, inputs, -1), HANDSIM_INVALID_ARGUMENT,
         "hand_count: must be >= 0");
  REJECT(world, handsim_step_hands(world, SCENARIO_DT, inputs, 2), HANDSIM_INVALID_ARGUMENT,
         "hands: got 2 entries but the world has 1 hands");
  inputs[0].hand = 0;
  REJECT(world, handsim_step_hands(world, SCENARIO_DT, inputs, 1), HANDSIM_STALE_ID, "hands[0].hand: is the null id");
  inputs[0].hand = removed_hand;
  REJECT(world, handsim_step_hands(world, SCENARIO_DT, inputs, 1), HANDSIM_STALE_ID,
         "hands[0].hand: names no live object");
  inputs[0].hand = hand;
  inputs[0].frame.joint_count = 25;
  REJECT(world, handsim_step_hands(world, SCENARIO_DT, inputs, 1), HANDSIM_INVALID_ARGUMENT,
         "hands[0].frame.joint_count: must be 26");
  inputs[0].frame = frames[0];
  inputs[0].frame.handedness = HANDSIM_LEFT;
  REJECT(world, handsim_step_hands(world, SCENARIO_DT, inputs, 1), HANDSIM_INVALID_ARGUMENT,
         "hands[0].frame.handedness: does not match");

  /* ids */
  REJECT(world, handsim_body_pose(world, stale, &pose), HANDSIM_STALE_ID, "body: names no live object");
  REJECT(world, handsim_body_pose(world, foreign, &pose), HANDSIM_STALE_ID, "body: names no live object");
  REJECT(world, handsim_body_pose(world, 0, &pose), HANDSIM_STALE_ID, "body: is the null id");
  REJECT(world, handsim_remove_body(world, stale), HANDSIM_STALE_ID, "body:");
  REJECT(world, handsim_remove_hand(world, box.lid), HANDSIM_STALE_ID, "hand:");
  REJECT(world, handsim_get_joint_state(world, box.lid, NULL), HANDSIM_INVALID_ARGUMENT, "out_state: must not be null");
  REJECT(world, handsim_stage_summary(world, NULL, 0, NULL), HANDSIM_INVALID_ARGUMENT, "length: must not be null");
  REJECT(world, handsim_remove_joint(world, 12345), HANDSIM_STALE_ID, "joint:");
  {
    handsim_body_id two[2];
    handsim_pose out[2];
    two[0] = box.lid;
    two[1] = stale;
    out[0].position.x = 42;
    REJECT(world, handsim_body_poses(world, two, 2, out), HANDSIM_STALE_ID, "bodies[1]: names no live body");
    CHECK(out[0].position.x == 42, "body_poses wrote before it failed");
  }

  /* null pointers */
  REJECT(world, handsim_body_pose(world, box.lid, NULL), HANDSIM_INVALID_ARGUMENT, "out_pose: must not be null");
  REJECT(NULL, handsim_body_pose(NULL, box.lid, &pose), HANDSIM_INVALID_ARGUMENT, "world: must not be null");
  REJECT(NULL, handsim_body_pose((const handsim_world*)fake_world, box.lid, &pose), HANDSIM_INVALID_ARGUMENT,
         "world: is not a live handsim world");
  REJECT(NULL, handsim_world_create(NULL, NULL), HANDSIM_INVALID_ARGUMENT, "out_world: must not be null");
  REJECT(world, handsim_add_body(world, NULL, &id), HANDSIM_INVALID_ARGUMENT, "body: must not be null");
  REJECT(world, handsim_set_body_pose(world, box.base, NULL), HANDSIM_INVALID_ARGUMENT, "pose: must not be null");
  REJECT(world, handsim_events(world, NULL, 0, NULL), HANDSIM_INVALID_ARGUMENT, "count: must not be null");
  REJECT(world, handsim_jewelry_box_lid_pinch_palm(world, NULL, HANDSIM_RIGHT, 0, 0, &palm),
         HANDSIM_INVALID_ARGUMENT, "box: must not be null");

  /* buffers */
  small[0].x = 42;
  REJECT(world, handsim_hand_particles(world, hand, 0, small, 10, &n), HANDSIM_INVALID_ARGUMENT,
         "out_positions: capacity 10 is too small, needs 1182");
  CHECK(n == 1182 && small[0].x == 42, "a too-small buffer: count %d, the buffer untouched", (int)n);
  REJECT(world, handsim_hand_particles(world, hand, 0, NULL, 5, &n), HANDSIM_INVALID_ARGUMENT,
         "out_positions: must not be null when capacity is 5");
  REJECT(world, handsim_hand_particles(world, hand, 0, small, -1, &n), HANDSIM_INVALID_ARGUMENT, "capacity: must be >= 0");
  REJECT(world, handsim_hand_render_vertices(world, hand, small, 10, &n), HANDSIM_INVALID_ARGUMENT,
         "out_vertices: capacity 10 is too small");
  REJECT(world, handsim_make_hand_frame(HANDSIM_RIGHT, &palm, &shape, joints, 25), HANDSIM_INVALID_ARGUMENT,
         "out_joints: capacity 25 is too small, needs 26");
  REJECT(NULL, handsim_layout(100000, &entry), HANDSIM_INVALID_ARGUMENT, "index: must be in 0..");

  /* definitions */
  MUST(handsim_body_def_default(&def));
  def.mass = -1;
  REJECT(world, handsim_add_body(world, &def, &id), HANDSIM_INVALID_ARGUMENT, "body.mass: must be 0 (static) or in [1e-06, 1e+06] kg");
  def.mass = 1;
  def.shape.type = 42;
  REJECT(world, handsim_add_body(world, &def, &id), HANDSIM_INVALID_ARGUMENT, "body.shape.type: unknown shape type 42");
  def.shape.type = HANDSIM_SHAPE_CONVEX_HULL;
  def.shape.point_count = 4;
  REJECT(world, handsim_add_body(world, &def, &id), HANDSIM_INVALID_ARGUMENT, "body.shape.points: must not be null");
  MUST(handsim_body_def_default(&def));
  def.pose.orientation.w = 2;
  REJECT(world, handsim_add_body(world, &def, &id), HANDSIM_INVALID_ARGUMENT, "body.pose.orientation:");
  MUST(handsim_hinge_def_default(&hd));
  hd.parent = box.base;
  hd.child = box.table;
  hd.lower = 1;
  hd.upper = 0;
  REJECT(world, handsim_add_hinge(world, &hd, &id), HANDSIM_INVALID_ARGUMENT, "hinge.");
  hd.lower = 0;
  hd.upper = 1;
  hd.child = box.lid;
  REJECT(world, handsim_add_hinge(world, &hd, &id), HANDSIM_INVALID_STATE, "hinge");
  hd.model = 9;
  REJECT(world, handsim_add_hinge(world, &hd, &id), HANDSIM_INVALID_ARGUMENT, "hinge.model: unknown joint model 9");
  MUST(handsim_ball_def_default(&bd));
  bd.parent = box.base;
  bd.child = box.lid;
  bd.solver = HANDSIM_SOLVER_LM;
  REJECT(world, handsim_add_ball(world, &bd, &id), HANDSIM_UNSUPPORTED, "ball.solver: the ball joint supports only");
  REJECT(world, handsim_set_joint_value(world, box.hinge, NAN), HANDSIM_INVALID_ARGUMENT, "value: must be finite");
  REJECT(world, handsim_remove_body(world, box.lid), HANDSIM_INVALID_STATE, "body: a joint still uses it");
  REJECT(world, handsim_set_body_pose(world, box.lid, &palm), HANDSIM_INVALID_STATE, "body: is the child of a hard joint");
  palm.position.y = NAN;
  REJECT(world, handsim_make_hand_frame(HANDSIM_RIGHT, &palm, &shape, joints, HANDSIM_HAND_JOINT_COUNT),
         HANDSIM_INVALID_ARGUMENT, "palm_pose.position: must be finite");
  palm.position.y = 1;
  shape.curl_ring = NAN;
  REJECT(world, handsim_make_hand_frame(HANDSIM_RIGHT, &palm, &shape, joints, HANDSIM_HAND_JOINT_COUNT),
         HANDSIM_INVALID_ARGUMENT, "params.curl_ring: must be finite");
  REJECT(world, handsim_bind_frame(3, 1.0, joints, HANDSIM_HAND_JOINT_COUNT), HANDSIM_INVALID_ARGUMENT, "handedness:");
  REJECT(world, handsim_closing_grip(NULL, 0.1, SCENARIO_CLOSING_S, &shape), HANDSIM_INVALID_ARGUMENT,
         "grip: must not be null");
  REJECT(world, handsim_closing_grip(&shape, NAN, SCENARIO_CLOSING_S, &shape), HANDSIM_INVALID_ARGUMENT,
         "t: must be finite");
  REJECT(world, handsim_closing_grip(&shape, 0.1, 0.0, &shape), HANDSIM_INVALID_ARGUMENT, "duration: must be finite and > 0");
  REJECT(world, handsim_open_grip(&shape, 1.5, &shape), HANDSIM_INVALID_ARGUMENT, "openness:");
  REJECT(world, handsim_open_grip(&shape, 0.5, NULL), HANDSIM_INVALID_ARGUMENT, "out_params: must not be null");
  {
    handsim_hand_def hand_def;
    MUST(handsim_hand_def_default(&hand_def));
    hand_def.particle_count = 0;
    REJECT(world, handsim_add_hand(world, &hand_def, &id), HANDSIM_INVALID_ARGUMENT, "def.particle_count: must be in 1..100000");
  }
  {
    handsim_jewelry_box_def jd;
    handsim_jewelry_box other_box;
    MUST(handsim_jewelry_box_def_default(&jd));
    jd.lid_mass = 0;
    REJECT(world, handsim_build_jewelry_box(world, &jd, &other_box), HANDSIM_INVALID_ARGUMENT,
           "jewelry_box.lid_mass: must be > 0");
  }
  MUST(handsim_world_settings_default(&settings));
  settings.fixed_substep = 0;
  REJECT(NULL, handsim_world_create(&settings, &other), HANDSIM_INVALID_ARGUMENT, "settings.fixed_substep: must be");
  MUST(handsim_world_settings_default(&settings));
  settings.grasp.grasp_time_s = -1;
  REJECT(NULL, handsim_world_create(&settings, &other), HANDSIM_INVALID_ARGUMENT, "settings.grasp.grasp_time_s");
  MUST(handsim_world_settings_default(&settings));
  settings.particle_contacts = 5;
  REJECT(NULL, handsim_world_create(&settings, &other), HANDSIM_INVALID_ARGUMENT, "settings.particle_contacts");
  MUST(handsim_world_settings_default(&settings));
  settings.push_model = HANDSIM_PUSH_WRAP + 1;  /* one past the last model */
  REJECT(NULL, handsim_world_create(&settings, &other), HANDSIM_INVALID_ARGUMENT, "settings.push_model");

  /* the world still steps after all that, exactly as before */
  MUST(handsim_step(world, SCENARIO_DT, frames, 1));
  MUST(handsim_world_destroy(world));
  MUST(handsim_world_destroy(other));
}

/* --- struct layouts: what this C compiler sees against what the library was compiled with --------------------- */

typedef struct c_layout {
  const char* struct_name;
  const char* field_name;
  size_t offset, size;
} c_layout;

#define HANDSIM_LAYOUT_STRUCT(s) {#s, NULL, 0, sizeof(s)},
#define HANDSIM_LAYOUT_FIELD(s, f) {#s, #f, offsetof(s, f), sizeof(((s*)0)->f)},
static const c_layout kCLayout[] = {
#include "handsim_layout.inc"
};
#undef HANDSIM_LAYOUT_STRUCT
#undef HANDSIM_LAYOUT_FIELD

static void test_layout(void) {
  int32_t count = 0, i;
  const int32_t expected = (int32_t)(sizeof kCLayout / sizeof kCLayout[0]);
  MUST(handsim_layout_count(&count));
  CHECK(count == expected, "the library lists %d layout rows, this C file %d", (int)count, (int)expected);
  printf("struct layouts (C compiler: sizeof / offsetof):\n");
  for (i = 0; i < count && i < expected; ++i) {
    handsim_layout_entry e;
    const c_layout* c = &kCLayout[i];
    MUST(handsim_layout(i, &e));
    if (c->field_name)
      printf("    %-12s offset %3u size %2u\n", c->field_name, (unsigned)c->offset, (unsigned)c->size);
    else
      printf("  %-26s sizeof %u\n", c->struct_name, (unsigned)c->size);
    CHECK(strcmp(e.struct_name, c->struct_name) == 0 &&
              ((e.field_name == NULL && c->field_name == NULL) ||
               (e.field_name && c->field_name && strcmp(e.field_name, c->field_name) == 0)) &&
              (size_t)e.offset == c->offset && (size_t)e.size == c->size,
          "%s.%s: library offset %d size %d, C offset %u size %u", c->struct_name,
          c->field_name ? c->field_name : "", (int)e.offset, (int)e.size, (unsigned)c->offset, (unsigned)c->size);
  }
}

/* --- enums: every row of the core's table is a constant of handsim.h with the core's number, and the library
 * lists the same rows (a constant missing from handsim.h does not compile) ---------------------------------- */

typedef struct c_enum {
  const char* enum_name;
  const char* value_name;
  const char* constant;
  int table_value, header_value;
} c_enum;

#define HANDSIM_C_ENUM_ROW(Enum, Value, number, UPPER, C_CONSTANT) {#Enum, #Value, #C_CONSTANT, number, C_CONSTANT},
static const c_enum kCEnums[] = {HANDSIM_ENUM_VALUES(HANDSIM_C_ENUM_ROW)};
#undef HANDSIM_C_ENUM_ROW

static void test_enums(void) {
  int32_t count = 0, i;
  const int32_t expected = (int32_t)(sizeof kCEnums / sizeof kCEnums[0]);
  MUST(handsim_enum_count(&count));
  CHECK(count == expected, "the library lists %d enum values, the table %d", (int)count, (int)expected);
  for (i = 0; i < count && i < expected; ++i) {
    handsim_enum_entry e;
    const c_enum* c = &kCEnums[i];
    MUST(handsim_enum_value(i, &e));
    CHECK(c->header_value == c->table_value, "%s is %d in handsim.h, %d in the table", c->constant, c->header_value,
          c->table_value);
    CHECK(strcmp(e.enum_name, c->enum_name) == 0 && strcmp(e.value_name, c->value_name) == 0 &&
              strcmp(e.constant, c->constant) == 0 && e.value == c->table_value,
          "row %d: library %s::%s %s = %d, table %s::%s %s = %d", (int)i, e.enum_name, e.value_name, e.constant,
          (int)e.value, c->enum_name, c->value_name, c->constant, c->table_value);
  }
  REJECT(NULL, handsim_enum_value(count, NULL), HANDSIM_INVALID_ARGUMENT, "out_entry: must not be null");
  {
    handsim_enum_entry e;
    REJECT(NULL, handsim_enum_value(-1, &e), HANDSIM_INVALID_ARGUMENT, "index: must be in 0..");
  }
  printf("enums: %d values, each a constant of handsim.h\n", (int)count);
}

/* --- mirrored defs: every field of a C struct that mirrors a core def is a row of the def table (the library's
 * build already fails on a row without its C field) ------------------------------------------------------------ */

typedef struct c_def_field {
  const char* def;
  const char* field;
} c_def_field;

#define HANDSIM_C_DEF_ROW(Def, field) {#Def, #field},
#define HANDSIM_C_DEF_ROWS(Def, CStruct, ROWS) ROWS(HANDSIM_C_DEF_ROW)
static const c_def_field kCDefFields[] = {HANDSIM_DEFS(HANDSIM_C_DEF_ROWS)};
#undef HANDSIM_C_DEF_ROWS
#define HANDSIM_C_DEF_PAIR(Def, CStruct, ROWS) {#Def, #CStruct},
static const c_def_field kCMirrors[] = {HANDSIM_DEFS(HANDSIM_C_DEF_PAIR)}; /* {def, C struct} */
#undef HANDSIM_C_DEF_PAIR
#undef HANDSIM_C_DEF_ROW

static int is_def_row(const char* def, const char* field) {
  size_t i;
  for (i = 0; i < sizeof kCDefFields / sizeof kCDefFields[0]; ++i)
    if (strcmp(kCDefFields[i].def, def) == 0 && strcmp(kCDefFields[i].field, field) == 0) return 1;
  return 0;
}

static void test_mirrored_defs(void) {
  int32_t count = 0, i;
  int checked = 0;
  size_t m;
  MUST(handsim_layout_count(&count));
  for (i = 0; i < count; ++i) {
    handsim_layout_entry e;
    MUST(handsim_layout(i, &e));
    if (!e.field_name || strcmp(e.field_name, "reserved") == 0) continue;
    for (m = 0; m < sizeof kCMirrors / sizeof kCMirrors[0]; ++m) {
      if (strcmp(kCMirrors[m].field, e.struct_name) != 0) continue;
      CHECK(is_def_row(kCMirrors[m].def, e.field_name), "%s.%s mirrors no field of %s in handsim/def_table.h",
            e.struct_name, e.field_name, kCMirrors[m].def);
      ++checked;
    }
  }
  CHECK(checked == (int)(sizeof kCDefFields / sizeof kCDefFields[0]), "%d mirrored C fields, %d def rows", checked,
        (int)(sizeof kCDefFields / sizeof kCDefFields[0]));
  printf("mirrored defs: %d C fields, each a row of the def table\n", checked);
}

/* The contacts rule differs from the default only in the hand's closing and opening (and the span's pinch reach), the
 * paper's from it in eq. 3's reading and hysteresis; a grip closes from open. */
static void test_grasp_rule_and_grips(void) {
  handsim_world_settings settings;
  handsim_grasp_settings contacts, paper, g;
  handsim_hand_pose_params pinch, p;
  MUST(handsim_world_settings_default(&settings));
  MUST(handsim_grasp_settings_contacts(&contacts));
  MUST(handsim_grasp_settings_paper(&paper));
  g = settings.grasp;
  CHECK(g.closing_distance > 0 && g.opening_distance > 0, "the default rule needs the hand to close and open");
  g.closing_distance = g.opening_distance = g.pinch_reach = 0;
  CHECK(memcmp(&g, &contacts, sizeof g) == 0,
        "the contacts rule differs from the default in more than closing/opening and the pinch reach");
  CHECK(paper.cos_threshold == 0.7 && !paper.across_parts && paper.grasp_time_s == 0 && paper.release_time_s == 0 &&
            paper.closing_distance == 0 && paper.opening_distance == 0 && paper.release_distance == contacts.release_distance,
        "the paper's rule");
  REJECT(NULL, handsim_grasp_settings_paper(NULL), HANDSIM_INVALID_ARGUMENT, "out_settings: must not be null");
  MUST(handsim_lid_pinch_shape(&pinch));
  MUST(handsim_closing_grip(&pinch, 0.0, SCENARIO_CLOSING_S, &p));
  CHECK(p.thumb_opposition == 0 && p.curl_index == 0 && p.scale == pinch.scale, "closing starts open");
  MUST(handsim_closing_grip(&pinch, SCENARIO_CLOSING_S, SCENARIO_CLOSING_S, &p));
  CHECK(memcmp(&p, &pinch, sizeof p) == 0, "closing ends at the grip");
  MUST(handsim_open_grip(&pinch, 0.5, &p));
  CHECK(p.thumb_opposition == 0.5 * pinch.thumb_opposition, "half open halves the opposition");
}

int main(int argc, char** argv) {
  if (argc < 2) {
    fprintf(stderr, "usage: %s <hash_out> [<reference_hash_file>]\n", argv[0]);
    return 2;
  }
  printf("libhandsim %s, ABI 0x%08x (header 0x%08x), features 0x%x\n", handsim_version(),
         (unsigned)handsim_abi_version(), (unsigned)HANDSIM_ABI_VERSION, (unsigned)handsim_features());
  CHECK(handsim_abi_version() >> 16 == HANDSIM_ABI_VERSION_MAJOR, "ABI major mismatch");
  CHECK(strcmp(handsim_status_name(HANDSIM_STALE_ID), "StaleId") == 0, "status names");
  test_layout();
  test_enums();
  test_mirrored_defs();
  test_grasp_rule_and_grips();
  test_scenario(argv[1], argc > 2 ? argv[2] : NULL);
  test_shapes_and_joints();
  test_step_report();
  test_hands_by_id();
  test_bad_inputs();
  test_save_restore();
  printf("%d checks, %d failures\n", g_checks, g_failures);
  return g_failures == 0 ? 0 : 1;
}
