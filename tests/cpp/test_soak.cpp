// Soak: the jewelry box opened and closed by a scripted hand, over and over, for HANDSIM_SOAK_FRAMES frames
// (default 10,000 = 2.8 min of simulated time; the documented 10^6-frame run is `scripts/soak`). Per window of
// HANDSIM_SOAK_WINDOW frames (default frames / 10) it records the largest hinge violation, limit overshoot and
// grasp error, and asserts that every state stays finite, that the hinge holds, and that nothing drifts: the
// last window is no worse than the first. HANDSIM_SOAK_CSV=path also writes the per-window table as CSV.
//
// The script, 360 frames (6 s at 60 Hz) per cycle, both hands HandDef defaults:
//   right hand    0- 40  at the pinch on the closed lid's lip (lid_pinch_palm; it arrives there open in one
//                        frame and closes to lid_pinch_shape in closing_grip's 0.25 s, as in scenario_frames)
//                        and grasps it
//                40-150  swings it open to A (cosine ease), 150-180 holds it there; A = 45..85 deg and the
//                        pinch's place along the lip (+-2 cm) change every cycle (golden-ratio sequences), so
//                        no two cycles are the same
//   even cycles 180-300  closes it again; 300-330 releases it: the thumb lets go of the lip (thumb_opposition
//                        0.5 -> 0 in 12 frames), then the hand rises 6 cm; 330-360 waits
//   odd cycles  180-210  releases it the same way at A (the rising hand may carry the lid to its 90-deg
//                        stop before the grasp ends), 210-360 swings back to 0 deg 6 cm above the lid; the
//                        lid falls shut onto its lower limit (from the stop, once the passing hand pushes it
//                        off)
//   left hand            rests still beside the base's left side (scenario_frames' left-hand pose at frame 0,
//                        fixed in the world), so the base is steadied but never chased if it moves.
// Grasp error, defined: while the right hand is the lid's primary grasping hand, let R(t) = P(t)^-1 L(t) be the
// lid's pose L in the frame of the tracked palm pose P (World::hand_palm_pose), and R0 = R at the frame the
// grasp began. The error is |R(t) f - R0 f|, f the middle of the lid's front edge in the lid frame (where the
// fingers hold it): how far the held point has slid in the hand since the grasp began (metres), and the angle
// of R0^-1 R(t) (radians). It is sampled on the "holding" frames only — from 10 frames after the swing starts
// until the release starts (frames 50-180 of every cycle, plus 180-300 of even cycles) — so that the intended
// release motion is not counted as error. The lid must be grasped on every holding frame.
// It runs with both grasp rules (grasp_rules.h); HANDSIM_SOAK_CSV is written by the run with the default one.
#include "grasp_rules.h"
#include "handsim/scenes.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <string>
#include <vector>

using namespace handsim;

namespace {

constexpr double kDt = 1.0 / 60.0;
constexpr double kDeg = M_PI / 180.0;
constexpr int kCycle = 360;

long env_or(const char* name, long fallback) {
  const char* v = std::getenv(name);
  return v && *v ? std::atol(v) : fallback;
}

double ease(double x) { return 0.5 * (1 - std::cos(M_PI * std::clamp(x, 0.0, 1.0))); }

// The right hand's commanded hinge angle, lift (along the lid's normal), how long ago it began to close its pinch
// and how far it has opened it again to let go of the lip (0 pinching .. 1 open: open_grip of lid_pinch_shape)
// for frame i, and whether the script is holding the lid.
struct Command {
  double angle = 0;
  double lift = 0;
  double closing_s = kGripClosingS;  // closing_grip's t: the pinch is closed from kGripClosingS on
  double let_go = 0;
  double shift = 0;  // m, sideways along the lip (the base's x axis)
  bool holding = false;
};

constexpr double kAway = 0.06;

// A release that starts at frame u0 of the cycle: the hand opens in 12 frames, then rises.
void release(Command& c, int u, int u0) {
  c.let_go = ease((u - u0) / 12.0);
  c.lift = kAway * ease((u - u0 - 12) / 18.0);
}

// Every cycle differs, so the run never repeats itself exactly: the opening angle (45..85 deg) and the pinch's
// sideways place on the lip (+-2 cm) follow the fractional parts of multiples of the golden ratio.
double cycle_fraction(long cycle, double step) {
  const double x = double(cycle) * step;
  return x - std::floor(x);
}

Command command(long i) {
  const int u = int(i % kCycle);
  const long cycle = i / kCycle;
  const bool even = cycle % 2 == 0;
  const double open = (45 + 40 * cycle_fraction(cycle, 0.6180339887498949)) * kDeg;
  Command c;
  c.shift = 0.02 * (2 * cycle_fraction(cycle, 0.3819660112501051) - 1);
  if (u < 40) {
    c.closing_s = u * kDt;  // at the pinch, closing it (the hand arrives there open in one frame)
  } else if (u < 150) {
    c.angle = open * ease((u - 40) / 110.0);
  } else if (u < 180) {
    c.angle = open;
  } else if (even) {
    if (u < 300) c.angle = open * (1 - ease((u - 180) / 120.0));
    else release(c, u, 300);
  } else {
    c.angle = u < 210 ? open : open * (1 - ease((u - 210) / 150.0));
    release(c, u, 180);
  }
  c.holding = (u >= 50 && u < 180) || (even && u >= 180 && u < 300);
  return c;
}

struct Window {
  long first = 0, last = 0;
  double violation = 0, overshoot = 0, grasp_error = 0, grasp_angle = 0, base_moved = 0;
  long grasps = 0, holding_frames = 0, holding_ungrasped = 0, min_angle_frames = 0;
};

bool finite(const Pose& p) { return p.position.allFinite() && p.orientation.coeffs().allFinite(); }

}  // namespace

class soak : public testing::TestWithParam<test::GraspRule> {};

TEST_P(soak, JewelryBoxOpenedAndClosedForeverDoesNotDrift) {
  const long frames = env_or("HANDSIM_SOAK_FRAMES", 10000);
  const long window = env_or("HANDSIM_SOAK_WINDOW", std::max(1L, frames / 10));
  ASSERT_GE(frames, 2 * kCycle);

  const WorldDef def = test::with_rule(GetParam());
  const bool default_rule = def.grasp.closing_distance == GraspSettings{}.closing_distance &&
                            def.grasp.opening_distance == GraspSettings{}.opening_distance;
  World world(def);
  const JewelryBox box = build_jewelry_box(world);
  const HandId right = world.add_hand(HandDef{});
  HandDef left_def;
  left_def.handedness = Handedness::Left;
  const HandId left_hand = world.add_hand(left_def);
  const HandFrame left = scenario_frames(box, world, 0)[1];
  const Vec3 base0 = world.body_pose(box.base).position;
  const Vec3 front(0, 0, box.def.base_half_extents.z() + 0.5 * box.def.lid_overhang);  // lid frame

  std::vector<Window> windows;
  bool was_grasped = false;
  Pose relative0;
  for (long i = 0; i < frames; ++i) {
    if (i % window == 0) windows.push_back(Window{i, i});
    Window& w = windows.back();
    w.last = i;
    const Command c = command(i);
    Pose palm = box.lid_pinch_palm(world, Handedness::Right, c.angle, c.lift);
    palm.position += world.body_pose(box.base).orientation * Vec3(c.shift, 0, 0);
    const HandPoseParams shape =
        c.let_go > 0 ? open_grip(lid_pinch_shape(), c.let_go) : closing_grip(lid_pinch_shape(), c.closing_s);
    world.step(kDt, {{right, make_hand_frame(Handedness::Right, palm, shape)}, {left_hand, left}});

    for (BodyId b : world.bodies()) {
      ASSERT_TRUE(finite(world.body_pose(b))) << "frame " << i;
      ASSERT_TRUE(world.body_linear_velocity(b).allFinite() && world.body_angular_velocity(b).allFinite())
          << "frame " << i;
    }
    const JointState s = world.joint_state(box.hinge);
    ASSERT_TRUE(std::isfinite(s.value) && std::isfinite(s.rate)) << "frame " << i;
    ASSERT_LE(s.violation, 1e-9) << "frame " << i;  // scene size 1 m
    ASSERT_GE(s.value, box.def.lower) << "frame " << i;
    ASSERT_LE(s.value, box.def.upper) << "frame " << i;
    w.violation = std::max(w.violation, s.violation);
    w.overshoot = std::max(w.overshoot, s.overshoot);
    w.base_moved = std::max(w.base_moved, (world.body_pose(box.base).position - base0).norm());

    const GraspInfo g = world.body_grasp(box.lid);
    const bool grasped = g.grasped && g.primary == right;
    const Pose relative = world.hand_palm_pose(right).inverse() * world.body_pose(box.lid);
    if (grasped && !was_grasped) {
      relative0 = relative;
      ++w.grasps;
    }
    was_grasped = grasped;
    if (c.holding) {
      ++w.holding_frames;
      if (!grasped) {
        ++w.holding_ungrasped;
      } else {
        w.grasp_error = std::max(w.grasp_error, (relative.transform(front) - relative0.transform(front)).norm());
        w.grasp_angle = std::max(w.grasp_angle, relative0.orientation.angularDistance(relative.orientation));
      }
    }
  }

  std::printf("soak: %ld frames (%.2f h simulated), windows of %ld frames\n", frames, frames * kDt / 3600, window);
  std::printf("%9s %9s %13s %11s %14s %12s %7s %10s %11s\n", "first", "last", "violation_m", "overshoot",
              "grasp_err_m", "grasp_rad", "grasps", "ungrasped", "base_moved");
  for (const Window& w : windows)
    std::printf("%9ld %9ld %13.3g %11.3g %14.3g %12.3g %7ld %10ld %11.3g\n", w.first, w.last, w.violation,
                w.overshoot, w.grasp_error, w.grasp_angle, w.grasps, w.holding_ungrasped, w.base_moved);
  const char* path = std::getenv("HANDSIM_SOAK_CSV");
  if (path && default_rule) {
    FILE* f = std::fopen(path, "w");
    ASSERT_NE(f, nullptr) << path;
    std::fprintf(f, "first,last,violation_m,overshoot_rad,grasp_error_m,grasp_error_rad,grasps,"
                    "holding_frames,holding_ungrasped,base_moved_m\n");
    for (const Window& w : windows)
      std::fprintf(f, "%ld,%ld,%.6g,%.6g,%.6g,%.6g,%ld,%ld,%ld,%.6g\n", w.first, w.last, w.violation, w.overshoot,
                   w.grasp_error, w.grasp_angle, w.grasps, w.holding_frames, w.holding_ungrasped, w.base_moved);
    std::fclose(f);
  }

  // No drift: every window grasps the lid once a cycle, never loses it while holding, never overshoots a limit,
  // its worst grasp error stays within 1.5 x the first window's + 1 um (1e-5 rad), its worst hinge violation
  // within 10 x the first window's (or 1e-12 m), and the base stays within 1 cm of where it started.
  const Window& first = windows.front();
  for (const Window& w : windows) {
    EXPECT_EQ(w.holding_ungrasped, 0) << "window from frame " << w.first;
    EXPECT_GE(w.grasps, (w.last - w.first + 1) / kCycle) << "window from frame " << w.first;
    EXPECT_EQ(w.overshoot, 0.0) << "window from frame " << w.first;
    EXPECT_LE(w.grasp_error, 1.5 * first.grasp_error + 1e-6) << "window from frame " << w.first;
    EXPECT_LE(w.grasp_angle, 1.5 * first.grasp_angle + 1e-5) << "window from frame " << w.first;
    EXPECT_LE(w.violation, std::max(1e-12, 10 * first.violation)) << "window from frame " << w.first;
    EXPECT_LT(w.base_moved, 0.01) << "window from frame " << w.first;
  }
  EXPECT_LT(first.grasp_error, 1e-3);  // the hand really holds the lid: under 1 mm of slide
}
HANDSIM_BOTH_GRASP_RULES(soak);
