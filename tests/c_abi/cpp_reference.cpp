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
#include <atomic>
#include <chrono>
#include <cinttypes>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <functional>
#include <string>
#include <thread>
#include <vector>

namespace {

using namespace handsim;
using Clock = std::chrono::steady_clock;

// Frame i of scenario.h's right hand through the C++ API: the lid pinch closing onto the lip, then swung.
HandFrame scenario_hand(const World& world, const JewelryBox& box, int i) {
  return make_hand_frame(Handedness::Right, box.lid_pinch_palm(world, Handedness::Right, scenario_angle(i)),
                         closing_grip(lid_pinch_shape(), scenario_grip_t(i), SCENARIO_CLOSING_S));
}

struct Run {
  uint64_t hash = 0;
  double step_seconds = 0;  // sum over the frames of the step call alone
};

Run run_cpp() {
  Run r;
  World world;
  const JewelryBox box = build_jewelry_box(world);
  world.add_hand(HandDef{});
  std::vector<HandFrame> frames(1);
  for (int i = 0; i < SCENARIO_FRAMES; ++i) {
    frames[0] = scenario_hand(world, box, i);
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
  handsim_hand_pose_params pinch;
  handsim_joint_pose joints[HANDSIM_HAND_JOINT_COUNT];
  MUST(handsim_world_create(nullptr, &world));
  MUST(handsim_build_jewelry_box(world, nullptr, &box));
  MUST(handsim_add_hand(world, nullptr, &hand));
  MUST(handsim_lid_pinch_shape(&pinch));
  const handsim_hand_frame frame{HANDSIM_RIGHT, HANDSIM_HAND_JOINT_COUNT, joints};
  for (int i = 0; i < SCENARIO_FRAMES; ++i) {
    handsim_pose palm;
    handsim_hand_pose_params shape;
    MUST(handsim_closing_grip(&pinch, scenario_grip_t(i), SCENARIO_CLOSING_S, &shape));
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

double median(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  return v.empty() ? 0 : v[v.size() / 2];
}

double stage_seconds(const StepReport& report) {
  double sum = 0;
  for (const StageReport& r : report.stages) sum += r.seconds;
  return sum;
}

double seconds_of(const std::function<void()>& f) {
  const auto t0 = Clock::now();
  f();
  return std::chrono::duration<double>(Clock::now() - t0).count();
}

// The scenario through both APIs in lockstep (two worlds, the same frames), each frame's two steps timed back to
// back in alternating order: on a loaded machine the noise hits both alike, and the median of the per-frame
// differences is the cost of going through the C ABI. Then a cheap query, World::body_pose against
// handsim_body_pose, in alternating batches.
void bench(int reps) {
  std::vector<double> cpp_steps, c_steps, differences;
  std::vector<double> cpp_outside, c_outside;  // a step's wall time minus what its stages report
  for (int rep = 0; rep < reps; ++rep) {
    World world;
    const JewelryBox box = build_jewelry_box(world);
    world.add_hand(HandDef{});
    std::vector<HandFrame> frames(1);
    handsim_world* cworld = nullptr;
    handsim_jewelry_box cbox;
    handsim_hand_id chand = 0;
    handsim_joint_pose joints[HANDSIM_HAND_JOINT_COUNT];
    const handsim_hand_frame cframe{HANDSIM_RIGHT, HANDSIM_HAND_JOINT_COUNT, joints};
    MUST(handsim_world_create(nullptr, &cworld));
    MUST(handsim_build_jewelry_box(cworld, nullptr, &cbox));
    MUST(handsim_add_hand(cworld, nullptr, &chand));
    for (int i = 0; i < SCENARIO_FRAMES; ++i) {
      frames[0] = scenario_hand(world, box, i);
      for (int j = 0; j < HANDSIM_HAND_JOINT_COUNT; ++j) {
        const JointPose& p = frames[0].joints[size_t(j)];
        const Quat& q = p.orientation;
        joints[j] = {{p.position.x(), p.position.y(), p.position.z()}, {q.x(), q.y(), q.z(), q.w()}, p.radius, 1, 0};
      }
      const auto cpp_step = [&] { world.step(SCENARIO_DT, frames); };
      const auto c_step = [&] { MUST(handsim_step(cworld, SCENARIO_DT, &cframe, 1)); };
      double t_cpp, t_c;
      if (i % 2 == 0) {
        t_cpp = seconds_of(cpp_step);
        t_c = seconds_of(c_step);
      } else {
        t_c = seconds_of(c_step);
        t_cpp = seconds_of(cpp_step);
      }
      cpp_steps.push_back(t_cpp);
      c_steps.push_back(t_c);
      differences.push_back(t_c - t_cpp);
      cpp_outside.push_back(t_cpp - stage_seconds(world.last_step()));
      handsim_step_report report;
      MUST(handsim_last_step(cworld, &report));
      double in_stages = 0;
      for (const handsim_step_stage& s : report.stages) in_stages += s.seconds;
      c_outside.push_back(t_c - in_stages);
    }
    uint64_t chash = 0;
    MUST(handsim_state_hash(cworld, &chash));
    MUST(handsim_world_destroy(cworld));
    if (chash != world.state_hash()) {
      std::fprintf(stderr, "FAIL: the lockstep worlds diverged\n");
      std::exit(1);
    }
  }
  std::printf("scenario step, %d runs x %d frames in lockstep, medians: C++ %.2f us/step, C ABI %.2f us/step, "
              "per-frame difference %+.2f us\n",
              reps, SCENARIO_FRAMES, 1e6 * median(cpp_steps), 1e6 * median(c_steps), 1e6 * median(differences));
  std::printf("scenario step outside the core's stages (call, validation, frame copy), medians: C++ %.2f us, "
              "C ABI %.2f us\n",
              1e6 * median(cpp_outside), 1e6 * median(c_outside));

  World world;
  const JewelryBox box = build_jewelry_box(world);
  handsim_world* cworld = nullptr;
  handsim_jewelry_box cbox;
  MUST(handsim_world_create(nullptr, &cworld));
  MUST(handsim_build_jewelry_box(cworld, nullptr, &cbox));
  volatile double sink = 0;
  const int calls = 100000;
  std::vector<double> direct, via_c;
  for (int batch = 0; batch < 20 * reps; ++batch) {
    direct.push_back(seconds_of([&] {
      for (int i = 0; i < calls; ++i) sink = sink + world.body_pose(box.lid).position.y();
    }) / calls);
    via_c.push_back(seconds_of([&] {
      for (int i = 0; i < calls; ++i) {
        handsim_pose p;
        handsim_body_pose(cworld, cbox.lid, &p);
        sink = sink + p.position.y;
      }
    }) / calls);
  }
  std::printf("body pose query, %d batches x %d calls, medians: C++ %.1f ns/call, C ABI %.1f ns/call\n", 20 * reps,
              calls, 1e9 * median(direct), 1e9 * median(via_c));
  MUST(handsim_world_destroy(cworld));
}

// The threading rules of handsim.h: worlds on different threads step concurrently and identically, and each
// thread reads its own last error.
bool threads_are_independent(uint64_t expected_hash) {
  std::atomic<int> failures{0};
  auto worker = [&](int k) {
    if (run_c_abi().hash != expected_hash) ++failures;
    handsim_pose pose;
    handsim_layout_entry entry;
    const int status = k == 0 ? handsim_body_pose(nullptr, 0, &pose) : handsim_layout(-1, &entry);
    for (int i = 0; i < 1000; ++i) std::this_thread::yield();  // let the other thread fail in between
    const std::string expected = k == 0 ? "world: must not be null" : "index: must be in 0..";
    if (status != HANDSIM_INVALID_ARGUMENT || std::string(handsim_last_error()).rfind(expected, 0) != 0) ++failures;
  };
  std::thread a(worker, 0), b(worker, 1);
  a.join();
  b.join();
  std::printf("two threads, two worlds: %s\n", failures == 0 ? "same hash, own last error" : "FAILED");
  return failures == 0;
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
  if (!threads_are_independent(cpp.hash)) return 1;
  if (argc == 4) bench(std::max(1, std::atoi(argv[3])));
  return 0;
}
