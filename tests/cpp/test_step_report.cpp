// The typed step report (handsim/step_report.h): each stage's work or skip reason, the warnings, and the
// per-step solve fields of JointState cleared each step.
#include "handsim/scenes.h"
#include "handsim/world.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <chrono>
#include <cmath>

using namespace handsim;

namespace {
constexpr double kDt = 1.0 / 60;
}

TEST(StepReport, AnEmptyWorldSkipsEveryHandStageWithItsReason) {
  World w;
  const StepReport r = w.step(kDt);
  EXPECT_EQ(r.stage(Stage::Skinning).skip, SkipReason::NoTrackedHand);
  EXPECT_EQ(r.stage(Stage::Contacts).skip, SkipReason::NoHandNearBody);
  EXPECT_EQ(r.stage(Stage::Deformation).skip, SkipReason::NoParticleInside);
  EXPECT_EQ(r.stage(Stage::Grasp).skip, SkipReason::NoMovableBodyTouched);
  EXPECT_EQ(r.stage(Stage::Attach).skip, SkipReason::NothingGrasped);
  EXPECT_EQ(r.stage(Stage::PoseFit).skip, SkipReason::NoFreeBodyTouched);
  EXPECT_EQ(r.stage(Stage::Joints).skip, SkipReason::NoJoints);
  EXPECT_EQ(r.stage(Stage::Slip).skip, SkipReason::NoSecondHand);
  // 1/60 s is four 1/240 s substeps; with no dynamic body Bullet has nothing to do (after the first step,
  // which syncs it).
  EXPECT_TRUE(r.stage(Stage::Dynamics).ran());
  EXPECT_EQ(r.stage(Stage::Dynamics).work, 4);
  EXPECT_EQ(r.substeps, 4);
  EXPECT_FALSE(w.step(kDt).bullet);
  EXPECT_EQ(r.warnings, 0u);
  for (size_t k = 0; k < kStageCount; ++k) EXPECT_EQ(r.stages[k].stage, Stage(int(k)));
  EXPECT_EQ(std::string(r.stage(Stage::PoseFit).name()), "pose_fit");
  // last_step keeps what step returned; the summary is made from it.
  EXPECT_EQ(w.last_step().stage(Stage::Joints).skip, SkipReason::NoJoints);
  EXPECT_NE(w.stage_summary().find("joints       skip"), std::string::npos) << w.stage_summary();
  EXPECT_NE(w.stage_summary().find("skip: no joints"), std::string::npos) << w.stage_summary();
}

TEST(StepReport, ADtBelowOneSubstepSkipsDynamics) {
  World w;
  const StepReport r = w.step(0.5 / 240);
  EXPECT_EQ(r.stage(Stage::Dynamics).skip, SkipReason::BelowSubstep);
  EXPECT_EQ(r.substeps, 0);
  // The half substep is kept: the next half completes one.
  EXPECT_EQ(w.step(0.5 / 240).substeps, 1);
}

TEST(StepReport, AHugeDtDropsSubstepsAndSaysHowMuch) {
  World w;
  BodyDef box;
  box.shape = ShapeDef::box(Vec3(0.05, 0.05, 0.05));
  box.pose.position = Vec3(0, 1, 0);
  w.add_body(box);
  const StepReport r = w.step(1.0);  // 240 substeps of 1/240 s, at most 8 run
  EXPECT_TRUE(r.has(StepWarning::SubstepsDropped));
  EXPECT_EQ(r.substeps, 8);
  EXPECT_TRUE(r.bullet);  // the falling box
  EXPECT_NEAR(r.dropped_seconds, 1.0 - 8.0 / 240, 1e-12);
  EXPECT_NE(w.stage_summary().find("beyond max_substeps dropped"), std::string::npos);
  const StepReport next = w.step(kDt);
  EXPECT_FALSE(next.has(StepWarning::SubstepsDropped));
  EXPECT_EQ(next.dropped_seconds, 0.0);
  EXPECT_EQ(next.substeps, 4);
}

TEST(StepReport, APalmJumpingFasterThanTheSpeedCapWarns) {
  World w;
  const HandId hand = w.add_hand(HandDef{});
  const Pose here{Vec3(0, 0.3, 0), Quat::Identity()};
  EXPECT_EQ(w.step(kDt, {{hand, make_hand_frame(Handedness::Right, here)}}).warnings, 0u);
  EXPECT_EQ(w.step(kDt, {{hand, make_hand_frame(Handedness::Right, here)}}).warnings, 0u);
  const Pose far{Vec3(1e6, 0.3, 0), Quat::Identity()};  // 6e7 m/s, beyond the 1e4 m/s cap
  const StepReport jump = w.step(kDt, {{hand, make_hand_frame(Handedness::Right, far)}});
  EXPECT_TRUE(jump.has(StepWarning::HandTeleported));
  EXPECT_EQ(jump.stage(Stage::Skinning).work, 1);
  EXPECT_FALSE(w.step(kDt, {{hand, make_hand_frame(Handedness::Right, far)}}).has(StepWarning::HandTeleported));
}

// JointState's solve fields describe this step's solve only: the frame after the hand leaves they are cleared.
TEST(StepReport, JointSolvedIsClearedTheFrameAfterTheHandLeaves) {
  World world;
  JewelryBox box = build_jewelry_box(world);
  const HandId hand = world.add_hand(HandDef{});
  for (int i = 0; i < 50; ++i) {  // the hand closes its pinch on the lip (closing_grip: 15 frames), then swings
    const double angle = std::clamp((i - 20) / 30.0, 0.0, 1.0) * 0.5;
    world.step(kDt, {{hand, make_hand_frame(Handedness::Right, box.lid_pinch_palm(world, Handedness::Right, angle),
                                             closing_grip(lid_pinch_shape(), i * kDt))}});
  }
  ASSERT_TRUE(world.body_grasp(box.lid).grasped);
  const JointState held = world.joint_state(box.hinge);
  ASSERT_TRUE(held.solved);
  world.remove_hand(hand);
  const StepReport r = world.step(kDt);
  EXPECT_EQ(r.stage(Stage::Joints).work, 1);
  const JointState after = world.joint_state(box.hinge);
  EXPECT_FALSE(after.solved);
  EXPECT_EQ(after.cost, 0.0);
  EXPECT_EQ(after.iterations, 0);
  EXPECT_EQ(after.solve_seconds, 0.0);
}

// A stage's seconds run from the end of the stage before (one clock read a stage): every stage's are positive, and
// together they take no more than the step did as its caller timed it, frame after frame of a lid pinched and lifted.
TEST(StepReport, TheStagesSecondsAreSuccessiveSpansOfTheStep) {
  World w{WorldDef{}};
  const JewelryBox box = build_jewelry_box(w);
  const HandId hand = w.add_hand(HandDef{});
  for (int i = 0; i < 60; ++i) {
    const Pose palm = box.lid_pinch_palm(w, Handedness::Right, 0.005 * i);
    const HandFrame frame = make_hand_frame(Handedness::Right, palm, closing_grip(lid_pinch_shape(), i * kDt));
    const auto t0 = std::chrono::steady_clock::now();
    const StepReport r = w.step(kDt, {{hand, frame}});
    const double wall = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    double sum = 0;
    for (const StageReport& s : r.stages) {
      EXPECT_GT(s.seconds, 0.0) << s.name() << " at frame " << i;
      sum += s.seconds;
    }
    EXPECT_LE(sum, wall) << "frame " << i;
  }
}
