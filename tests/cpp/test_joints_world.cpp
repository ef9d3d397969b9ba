// Jointed objects in the world: hard groups never leave their joint or pass a limit, free joints follow
// analytic dynamics, the micro-simulator moves a grasped lid, bad joint definitions are rejected.
#include "grasp_rules.h"
#include "handsim/scenes.h"
#include "world_impl.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <random>

using namespace handsim;

namespace {

constexpr double kDt = 1.0 / 60.0;
constexpr double kDeg = M_PI / 180.0;

BodyDef box_body(const Vec3& half, const Vec3& position, double mass) {
  BodyDef d;
  d.shape = ShapeDef::box(half);
  d.pose.position = position;
  d.mass = mass;
  return d;
}

// A rod hanging from a world hinge: the classic compound pendulum.
struct Pendulum {
  World world{[] {
    WorldDef d;
    d.ground = false;
    return d;
  }()};
  BodyId rod;
  JointId hinge;
  double length = 0.4;

  explicit Pendulum(double angle0, double lower = -kUnlimited, double upper = kUnlimited) {
    rod = world.add_body(box_body(Vec3(0.01, 0.5 * length, 0.01), Vec3(0, -0.5 * length, 0), 1.0));
    HingeDef h;
    h.child = rod;
    h.pivot_parent = Vec3::Zero();
    h.axis_parent = Vec3::UnitZ();
    h.pivot_child = Vec3(0, 0.5 * length, 0);
    h.axis_child = Vec3::UnitZ();
    h.lower = lower;
    h.upper = upper;
    hinge = world.add_joint(h);
    world.set_joint_value(hinge, angle0);
  }
};

// The jewelry box on a fixed base (it keeps a test about the lid), under Wrap, with one hand: the world of the
// lid tests that compare frame rates.
struct FixedBaseLid {
  World world{[] {
    WorldDef d;
    d.push_model = PushModel::Wrap;
    return d;
  }()};
  JewelryBox box = [this] {
    JewelryBoxDef def;
    def.base_mass = 0;
    return build_jewelry_box(world, def);
  }();
  HandId hand = world.add_hand(HandDef{});
};

// The hand scripts below close their pinch on the lid (closing_grip) before they swing it: each runs with both
// grasp rules (grasp_rules.h).
class JointsWorldHand : public testing::TestWithParam<test::GraspRule> {};

// The lid pinch at `angle`, `t` s after the hand arrived open and began to close it.
HandFrame pinch(const JewelryBox& box, const World& world, double angle, double t) {
  return make_hand_frame(Handedness::Right, box.lid_pinch_palm(world, Handedness::Right, angle),
                         closing_grip(lid_pinch_shape(), t));
}

}  // namespace

TEST(JointsWorld, CompoundPendulumPeriodMatchesAnalytic) {
  Pendulum p(2 * kDeg);
  // Small-angle period of a slender box rod about its end: 2 pi sqrt(I / (m g d)).
  const double L = p.length, w = 0.02;
  const double inertia = (L * L + w * w) / 12.0 + 0.25 * L * L;  // per kg, about the pivot
  const double period = 2 * M_PI * std::sqrt(inertia / (9.81 * 0.5 * L));
  // Zero crossings from + to -.
  std::vector<double> crossings;
  double previous = p.world.joint_state(p.hinge).value;
  for (int i = 0; i < 600; ++i) {
    p.world.step(kDt);
    const JointState s = p.world.joint_state(p.hinge);
    if (previous > 0 && s.value <= 0) crossings.push_back(p.world.time());
    previous = s.value;
    ASSERT_LE(s.violation, 1e-12);
  }
  ASSERT_GE(crossings.size(), 3u);
  const double measured = (crossings.back() - crossings.front()) / (crossings.size() - 1);
  EXPECT_NEAR(measured, period, 0.01 * period);
}

TEST(JointsWorld, FallingPendulumStopsAtItsLimitAndStaysOnTheHinge) {
  Pendulum p(80 * kDeg, -30 * kDeg, 85 * kDeg);
  double lowest = 1e9;
  for (int i = 0; i < 600; ++i) {
    p.world.step(kDt);
    const JointState s = p.world.joint_state(p.hinge);
    lowest = std::min(lowest, s.value);
    ASSERT_GE(s.value, -30 * kDeg - 1e-12);
    ASSERT_EQ(s.overshoot, 0.0);
    ASSERT_LE(s.violation, 1e-12);
  }
  EXPECT_NEAR(lowest, -30 * kDeg, 1e-12);  // it swung down through 0 and hit the lower limit
}

// Issue 22 item 3: a lid grasped and dragged past a stop near +-pi stays at that stop. Before, limits +-165
// deg jumped to -165 deg in one frame (rate -346 rad/s, overshoot 0) once the hand passed ~180 deg, and
// limits [-pi, pi] jumped 179 -> -177 deg: the solver took the admissible turn nearest in cost, not the
// one the lid reaches by moving. No gravity, no table, a static base: the lid stays wherever the hand leaves it.
TEST_P(JointsWorldHand, HingeDraggedPastAStopNearPiStaysAtTheStop) {
  for (const double stop : {165 * kDeg, M_PI}) {
    WorldDef wd = test::with_rule(GetParam());
    wd.gravity = Vec3::Zero();
    wd.ground = false;
    World world(wd);
    JewelryBoxDef bd;
    bd.table = false;
    bd.base_mass = 0;
    bd.lower = -stop;
    bd.upper = stop;
    const JewelryBox box = build_jewelry_box(world, bd);
    const HandId hand = world.add_hand(HandDef{});
    double previous = 0, max_value = 0, max_jump = 0;
    for (int i = 0; i < 340; ++i) {
      const double angle = std::clamp((i - 20) / 300.0, 0.0, 1.0) * 200 * kDeg;  // 0 -> 200 deg in 5 s
      world.step(kDt, {{hand, pinch(box, world, angle, i * kDt)}});
      const JointState s = world.joint_state(box.hinge);
      max_jump = std::max(max_jump, std::abs(s.value - previous));
      max_value = std::max(max_value, s.value);
      previous = s.value;
      ASSERT_LE(s.value, stop + 1e-12) << "frame " << i;
      ASSERT_EQ(s.overshoot, 0.0) << "frame " << i;
      ASSERT_LE(s.violation, 1e-9) << "frame " << i;
    }
    EXPECT_NEAR(max_value, stop, 1e-9) << "the hand dragged the lid to its stop";
    EXPECT_NEAR(previous, stop, 1e-9) << "and it stayed there";
    EXPECT_LE(max_jump, 0.1) << "no frame moved the lid more than the hand's swing (0.012 rad a frame)";
  }
}

// Ranges wider than 2 pi and stops far from 0: the angle counts turns. A pendulum a full turn and 1 rad out
// swings about 2 pi, never wrapped back to 0; one whose lower stop is at 2 pi + 0.2 falls onto that stop.
TEST(JointsWorld, HingeLimitsWiderThanTwoPiAndFarFromZeroHold) {
  Pendulum wide(2 * M_PI + 1.0, -3 * M_PI, 3 * M_PI);
  Pendulum far(2 * M_PI + 1.0, 2 * M_PI + 0.2, 3 * M_PI);
  EXPECT_NEAR(wide.world.joint_state(wide.hinge).value, 2 * M_PI + 1.0, 1e-12);
  double lowest = 1e9;
  for (int i = 0; i < 600; ++i) {
    wide.world.step(kDt);
    far.world.step(kDt);
    const JointState w = wide.world.joint_state(wide.hinge), f = far.world.joint_state(far.hinge);
    ASSERT_GE(w.value, 2 * M_PI - 1.0 - 1e-3) << "frame " << i;
    ASSERT_LE(w.value, 2 * M_PI + 1.0 + 1e-3) << "frame " << i;
    ASSERT_GE(f.value, 2 * M_PI + 0.2 - 1e-12) << "frame " << i;
    ASSERT_LE(f.overshoot, 1e-12);  // measured from the poses: rounding at 2 pi + 0.2 (8.9e-16 rad)
    ASSERT_LE(std::max(w.violation, f.violation), 1e-12);
    lowest = std::min(lowest, w.value);
  }
  EXPECT_LT(lowest, 2 * M_PI - 0.9) << "it did swing through 2 pi to the other side";
  EXPECT_NEAR(far.world.joint_state(far.hinge).value, 2 * M_PI + 0.2, 1e-12);
  // A joint made at a pose inside [3 pi, 5 pi] (a rest pose: 0 = 4 pi) takes 4 pi, not a jump to 3 pi.
  World world;
  const BodyId rod = world.add_body(box_body(Vec3(0.01, 0.2, 0.01), Vec3(0, 1, 0), 1.0));
  HingeDef h;
  h.child = rod;
  h.pivot_parent = Vec3(0, 1.2, 0);
  h.pivot_child = Vec3(0, 0.2, 0);
  h.axis_parent = h.axis_child = Vec3::UnitZ();
  h.lower = 3 * M_PI;
  h.upper = 5 * M_PI;
  const Pose before = world.body_pose(rod);
  const JointId j = world.add_joint(h);
  EXPECT_NEAR(world.joint_state(j).value, 4 * M_PI, 1e-12);
  EXPECT_LE((world.body_pose(rod).position - before.position).norm(), 1e-12);
}

TEST(JointsWorld, ClosedLidRestsAndOpenLidFallsShutWithoutPassingTheLimit) {
  World world;
  JewelryBox box = build_jewelry_box(world);
  for (int i = 0; i < 60; ++i) world.step(kDt);
  EXPECT_NEAR(world.joint_state(box.hinge).value, 0.0, 1e-12);
  world.set_joint_value(box.hinge, 60 * kDeg);
  double previous = 60 * kDeg;
  bool closed = false;
  for (int i = 0; i < 120; ++i) {
    world.step(kDt);
    const JointState s = world.joint_state(box.hinge);
    ASSERT_GE(s.value, 0.0);
    ASSERT_LE(s.value, previous + 1e-12);  // falls monotonically: the stop at 0 is inelastic
    ASSERT_LE(s.violation, 1e-9);
    previous = s.value;
    closed = closed || s.value == 0.0;
  }
  EXPECT_TRUE(closed);
}

TEST(JointsWorld, LidOpenAtItsUpperLimitStaysThere) {
  World world;
  JewelryBox box = build_jewelry_box(world);
  world.set_joint_value(box.hinge, 200 * kDeg);  // clamped
  EXPECT_EQ(world.joint_state(box.hinge).value, 0.5 * M_PI);
  for (int i = 0; i < 120; ++i) world.step(kDt);
  // Upright, the lid's centre of mass is just behind the hinge line, so gravity holds it on the limit.
  EXPECT_NEAR(world.joint_state(box.hinge).value, 0.5 * M_PI, 1e-12);
  EXPECT_EQ(world.joint_state(box.hinge).overshoot, 0.0);
}

TEST(JointsWorld, GroupRidesOnItsParent) {
  World world;
  JewelryBox box = build_jewelry_box(world);
  world.set_joint_value(box.hinge, 30 * kDeg);
  Pose moved = world.body_pose(box.base);
  moved.position += Vec3(0.05, 0, 0.02);
  moved.orientation = Quat(Eigen::AngleAxisd(0.3, Vec3::UnitY()));
  world.set_body_pose(box.base, moved);
  const JointState s = world.joint_state(box.hinge);
  EXPECT_NEAR(s.value, 30 * kDeg, 1e-15);
  EXPECT_LE(s.violation, 1e-12);
}

TEST_P(JointsWorldHand, GraspedLidDraggedPastItsLimitStaysAtTheLimitAndOnTheHinge) {
  World world(test::with_rule(GetParam()));
  JewelryBox box = build_jewelry_box(world);
  HandId hand = world.add_hand(HandDef{});
  double max_value = 0, max_violation = 0;
  bool grasped = false;
  // Close in for 20 frames, then swing the hand 180 degrees about the hinge over 3 s, and back, and again:
  // 10,000 frames in all.
  for (int i = 0; i < 10000; ++i) {
    const double phase = std::max(0, i - 20) / 180.0;  // 3 s per half swing
    const double angle = M_PI * (1 - std::cos(M_PI * std::fmod(phase, 2.0))) / 2;
    world.step(kDt, {{hand, pinch(box, world, angle, i * kDt)}});
    const JointState s = world.joint_state(box.hinge);
    grasped = grasped || world.body_grasp(box.lid).grasped;
    max_value = std::max(max_value, s.value);
    max_violation = std::max(max_violation, s.violation);
    ASSERT_LE(s.value, 0.5 * M_PI) << "frame " << i;
    ASSERT_GE(s.value, 0.0) << "frame " << i;
  }
  (void)hand;
  EXPECT_TRUE(grasped);
  EXPECT_NEAR(max_value, 0.5 * M_PI, 1e-12);  // the hand did drag it to the limit
  EXPECT_LE(max_violation, 1e-9);
}

TEST_P(JointsWorldHand, GraspedLidFollowsTheHandArcWithinLimits) {
  World world(test::with_rule(GetParam()));
  JewelryBox box = build_jewelry_box(world);
  const HandId hand = world.add_hand(HandDef{});
  for (int i = 0; i < 80; ++i) {
    const double angle = std::clamp((i - 20) / 60.0, 0.0, 1.0) * 60 * kDeg;
    world.step(kDt, {{hand, pinch(box, world, angle, i * kDt)}});
  }
  const JointState s = world.joint_state(box.hinge);
  EXPECT_TRUE(world.body_grasp(box.lid).grasped);
  EXPECT_TRUE(s.solved);
  // The hand holds the lid where it grabbed it, so the lid follows the hand's swing about the hinge.
  EXPECT_NEAR(s.value, 60 * kDeg, 2 * kDeg);
}

TEST(JointsWorld, LidPushedOpenByAFlatHandTurnsOnItsHinge) {
  World world;
  JewelryBoxDef def;
  def.base_mass = 0;  // the hand touches only the lid's lip; a fixed base keeps the test about the lid
  JewelryBox box = build_jewelry_box(world, def);
  const HandId hand = world.add_hand(HandDef{});
  // A flat hand, palm up, fingertips under the lip, rising 9 cm at a steady 9 cm/s: it pushes without
  // grasping.
  const Vec3 front = box.lid_front(world);
  double max_value = 0;
  for (int i = 0; i < 60; ++i) {
    const double rise = i * 0.0015;
    Pose palm{front + Vec3(0, -def.lid_half_thickness - 0.012 + rise, 0.11),
              Quat(Eigen::AngleAxisd(M_PI, Vec3::UnitZ()))};
    world.step(kDt, {{hand, make_hand_frame(Handedness::Right, palm, HandPoseParams{})}});
    const JointState s = world.joint_state(box.hinge);
    max_value = std::max(max_value, s.value);
    ASSERT_LE(s.violation, 1e-9);
    ASSERT_FALSE(world.body_grasp(box.lid).grasped);
  }
  EXPECT_GT(max_value, 30 * kDeg);
}

TEST(JointsWorld, SliderFallsLikeAFreeBodyUntilItsLimit) {
  WorldDef wd;
  wd.ground = false;
  World world(wd);
  BodyId block = world.add_body(box_body(Vec3::Constant(0.02), Vec3::Zero(), 0.3));
  SliderDef s;
  s.child = block;
  s.axis = Vec3::UnitY();
  s.lower = -0.5;
  s.upper = 0.5;
  JointId slider = world.add_joint(s);
  world.step(0.25);  // 60 substeps would exceed max_substeps; use frames
  for (int i = 0; i < 14; ++i) world.step(kDt);
  const double t = world.time() - 0.25 + 8 * wd.fixed_substep;  // the first frame ran max_substeps only
  const JointState st = world.joint_state(slider);
  EXPECT_NEAR(st.value, -0.5 * 9.81 * t * t, 0.01 * 0.5 * 9.81 * t * t + 2e-3);
  for (int i = 0; i < 120; ++i) world.step(kDt);
  EXPECT_EQ(world.joint_state(slider).value, -0.5);
  EXPECT_LE(world.joint_state(slider).violation, 1e-12);
  EXPECT_NEAR(world.body_pose(block).position.x(), 0.0, 1e-15);
}

// A hard child outside its parent is stopped by the parent's surface as at a limit, whatever its limits; one that
// starts inside its parent's shape (a drawer in a cabinet given as a solid box) is not (docs/grasp.md "A jointed
// child is stopped by its parent"). Two blocks on vertical sliders of +-0.5 m fall under gravity from a fixed box.
TEST(JointsWorld, ChildOutsideItsParentStopsOnItsSurfaceAndOneInsideSlidesThrough) {
  WorldDef wd;
  wd.ground = false;
  World world(wd);
  const BodyId cabinet = world.add_body(box_body(Vec3::Constant(0.1), Vec3::Zero(), 0.0));
  auto slide = [&](const Vec3& at) {
    SliderDef s;
    s.parent = cabinet;
    s.child = world.add_body(box_body(Vec3::Constant(0.02), at, 0.3));
    s.axis = Vec3::UnitY();
    s.lower = -0.5;
    s.upper = 0.5;
    return world.add_joint(s);
  };
  const JointId on_top = slide(Vec3(-0.05, 0.12, 0));  // resting on the top face (its bottom at y = 0.1)
  const JointId inside = slide(Vec3(0.05, 0.0, 0));
  const double start = world.joint_state(on_top).value;  // its height above the cabinet's centre, 0.12 m
  for (int i = 0; i < 60; ++i) world.step(kDt);
  const double fell = start - world.joint_state(on_top).value;
  EXPECT_GE(fell, 0.0);
  EXPECT_LE(fell, 0.0005);  // at most the stop's 0.5 mm slop into the top
  EXPECT_EQ(world.joint_state(inside).value, -0.5);  // fell through to its limit
}

// A runtime body of this shape at the origin, as add_body prepares it (the joint helpers' tests call them on bodies).
static Body body(const ShapeDef& shape) {
  Body b;
  b.shape = shape;
  b.prepared = prepare_shape(shape);
  return b;
}

// stopped_by_parent skips colliding the two shapes where their world boxes show that no point can lie deeper than
// the slop (may_lie_deeper): the bound must never skip a depth beyond it. Boxes and a hull (a wedge) posed at
// random about a parent box and a parent hull, at three depths; and a lid on its hinge at the base's top edge,
// at every angle, is skipped.
TEST(JointsWorld, TheWorldBoxBoundNeverSkipsAPointDeeperThanItsDepth) {
  const ShapeDef wedge = ShapeDef::convex_hull({{-0.03, 0, -0.02}, {0.03, 0, -0.02}, {-0.03, 0, 0.02},
                                                {0.03, 0, 0.02}, {-0.03, 0.04, -0.02}, {0.03, 0.04, -0.02}});
  const std::vector<Body> parents = {body(ShapeDef::box(Vec3(0.09, 0.04, 0.07))), body(wedge)};
  const std::vector<Body> children = {body(ShapeDef::box(Vec3(0.09, 0.0075, 0.0675))), body(wedge)};
  std::mt19937 rng(25);
  std::uniform_real_distribution<double> offset(-0.12, 0.12), unit(-1, 1);
  int skipped = 0, deeper = 0;
  for (const Body& parent : parents)
    for (const Body& child : children)
      for (int i = 0; i < 2000; ++i) {
        const Pose pose{Vec3(offset(rng), offset(rng), offset(rng)),
                        Quat(unit(rng), unit(rng), unit(rng), unit(rng)).normalized()};
        const double depth = depth_in(child, pose, parent);
        for (double bound : {0.0, 0.0005, 0.003}) {
          deeper += depth > bound;
          if (may_lie_deeper(child, pose, parent, bound)) continue;
          ++skipped;
          EXPECT_LE(depth, bound) << "parent " << int(parent.shape.type) << " child " << int(child.shape.type);
        }
      }
  EXPECT_GT(skipped, 1000);
  EXPECT_GT(deeper, 1000);
  // The jewelry box's lid hinged on its base's back top edge (the base's top at y = 0.04, the hinge along x at
  // z = -0.07): it meets the base at the hinge line only, opened or not.
  const Body& base = parents[0];
  const Body& lid = children[0];
  for (double angle = 0; angle <= 90 * kDeg; angle += 10 * kDeg) {
    const Quat open(Eigen::AngleAxisd(-angle, Vec3::UnitX()));
    const Vec3 hinge(0, 0.04, -0.07);
    const Pose pose{hinge + open * Vec3(0, 0.0075, 0.0675), open};
    EXPECT_FALSE(may_lie_deeper(lid, pose, base, 0.0005)) << angle;
  }
}

// may_lie_deeper remembers the parent's world box (Body::box_memo) with the pose and local box it was made from: one
// parent body moved between calls (often by one bit of one number, often not at all) and given another shape at the
// same pose answers as a copy of it that remembers nothing, every call.
TEST(JointsWorld, TheParentsRememberedWorldBoxFollowsItsPoseAndShape) {
  const Body big = body(ShapeDef::box(Vec3(0.09, 0.04, 0.07))), small = body(ShapeDef::box(Vec3(0.05, 0.04, 0.07)));
  const Body child = body(ShapeDef::box(Vec3(0.09, 0.0075, 0.0675)));
  std::mt19937 rng(25);
  std::uniform_real_distribution<double> offset(-0.12, 0.12), unit(-1, 1);
  Body parent = big;
  int answers[2] = {0, 0};
  for (int i = 0; i < 4000; ++i) {
    switch (rng() % 4) {
      case 0: parent.pose = Pose{Vec3(offset(rng), offset(rng), offset(rng)),
                                 Quat(unit(rng), unit(rng), unit(rng), unit(rng)).normalized()}; break;
      case 1: {
        double& x = parent.pose.position[int(rng() % 3)];
        x = std::nextafter(x, 1.0);
        break;
      }
      case 2: parent.prepared = (rng() % 2 ? big : small).prepared; break;
      default: break;  // not moved
    }
    Body fresh = parent;
    fresh.box_memo = WorldBoxMemo{};
    const Pose pose{Vec3(offset(rng), offset(rng), offset(rng)),
                    Quat(unit(rng), unit(rng), unit(rng), unit(rng)).normalized()};
    for (double bound : {0.0, 0.0005, 0.003}) {
      const bool got = may_lie_deeper(child, pose, parent, bound);
      ASSERT_EQ(got, may_lie_deeper(child, pose, fresh, bound)) << i << " " << bound;
      ++answers[got];
    }
    ASSERT_EQ(parent.box_memo.value().lo, fresh.box_memo.value().lo);
    ASSERT_EQ(parent.box_memo.value().hi, fresh.box_memo.value().hi);
  }
  EXPECT_GT(answers[0], 500);  // both answers are exercised
  EXPECT_GT(answers[1], 500);
}

TEST(JointsWorld, BallJointSettlesOnItsConeWhenGravityPullsOutside) {
  WorldDef wd;
  wd.ground = false;
  World world(wd);
  // At rest (R = identity) the bob hangs 40 degrees off vertical and may swing 30 degrees from there:
  // gravity pulls it towards the cone's edge.
  const Quat tilt(Eigen::AngleAxisd(40 * kDeg, Vec3::UnitZ()));
  BodyDef bd = box_body(Vec3(0.01, 0.1, 0.01), tilt * Vec3(0, -0.1, 0), 1.0);
  bd.pose.orientation = tilt;
  BodyId bob = world.add_body(bd);
  BallDef b;
  b.child = bob;
  b.pivot_child = Vec3(0, 0.1, 0);
  b.rest_orientation = tilt;
  b.pivot_parent = Vec3::Zero();
  b.cone_axis = -Vec3::UnitY();
  b.cone_half_angle = 30 * kDeg;
  b.damping = 0.001;
  JointId ball = world.add_joint(b);
  double max_violation = 0;
  for (int i = 0; i < 300; ++i) {
    world.step(kDt);
    const JointState s = world.joint_state(ball);
    ASSERT_LE(s.overshoot, 1e-12) << "frame " << i;
    max_violation = std::max(max_violation, s.violation);
  }
  EXPECT_LE(max_violation, 1e-12);
  // At rest on the cone's lowest line: 10 degrees from vertical.
  const Vec3 down = world.body_pose(bob).orientation * -Vec3::UnitY();
  EXPECT_NEAR(std::acos(-down.y()), 10 * kDeg, 0.5 * kDeg);
}

// A free ball joint conserves energy: an asymmetric box hung off-centre and released tumbles (gravity and the
// gyroscopic coupling between its axes) without gaining energy. The explicit gyroscopic term gained some every
// substep: the fuzz driver (issue 22 item 2) saw a ball child spin up from 35 to 1e19 rad/s and turn NaN.
TEST(JointsWorld, TumblingBallChildGainsNoEnergy) {
  WorldDef wd;
  wd.ground = false;
  World world(wd);
  const Vec3 half(0.12, 0.02, 0.06);
  const double mass = 2.0;
  const Quat start = Quat(Eigen::AngleAxisd(1.2, Vec3(1, 0.3, 0.5).normalized()));
  const Vec3 corner(0.1, 0.015, 0.04);  // the pivot on the child, near a corner: all three axes couple
  BodyDef bd = box_body(half, -(start * corner), mass);
  bd.pose.orientation = start;
  BodyId bob = world.add_body(bd);
  BallDef b;
  b.child = bob;
  b.pivot_child = corner;
  b.pivot_parent = Vec3::Zero();
  world.add_joint(b);
  const Vec3 inertia_body = mass / 3.0 * Vec3(half.y() * half.y() + half.z() * half.z(),
                                              half.x() * half.x() + half.z() * half.z(),
                                              half.x() * half.x() + half.y() * half.y());
  auto energy = [&] {
    const Pose p = world.body_pose(bob);
    const Vec3 w = p.orientation.conjugate() * world.body_angular_velocity(bob);
    const Vec3 v = world.body_linear_velocity(bob);
    return mass * 9.81 * p.position.y() + 0.5 * mass * v.squaredNorm() +
           0.5 * w.dot(inertia_body.cwiseProduct(w));
  };
  const double e0 = energy();
  double highest = e0, fastest = 0;
  for (int i = 0; i < 3000; ++i) {
    world.step(kDt);
    highest = std::max(highest, energy());
    fastest = std::max(fastest, world.body_angular_velocity(bob).norm());
  }
  // The swing's energy scale: m g times the drop from the start to the lowest the centre can hang.
  const double scale = mass * 9.81 * (corner.norm() + world.body_pose(bob).position.norm());
  EXPECT_LE(highest - e0, 0.02 * scale) << "fastest spin " << fastest << " rad/s";
  EXPECT_GT(fastest, 1.0);  // it did swing
}

TEST(JointsWorld, FixedChildFollowsItsParentExactly) {
  World world;
  BodyId a = world.add_body(box_body(Vec3::Constant(0.05), Vec3(0, 1, 0), 1.0));
  BodyId b = world.add_body(box_body(Vec3::Constant(0.02), Vec3(0.07, 1, 0), 0.2));
  FixedDef f;
  f.parent = a;
  f.child = b;
  f.relative.position = Vec3(0.07, 0, 0);
  JointId fixed = world.add_joint(f);
  for (int i = 0; i < 120; ++i) world.step(kDt);  // the parent falls and lands; the child rides along
  const Pose pa = world.body_pose(a), pb = world.body_pose(b);
  EXPECT_NEAR(pa.position.y(), 0.05, 2e-3);
  EXPECT_LE((pa.transform(Vec3(0.07, 0, 0)) - pb.position).norm(), 1e-12);
  EXPECT_LE(world.joint_state(fixed).violation, 1e-12);
}

TEST(JointsWorld, SoftHingeBaselineRunsAndIsMeasured) {
  World world;
  JewelryBoxDef def;
  def.model = JointModel::Soft;
  JewelryBox box = build_jewelry_box(world, def);
  world.set_joint_value(box.hinge, 60 * kDeg);
  double max_violation = 0;
  for (int i = 0; i < 120; ++i) {
    world.step(kDt);
    max_violation = std::max(max_violation, world.joint_state(box.hinge).violation);
  }
  EXPECT_NEAR(world.joint_state(box.hinge).value, 0.0, 3 * kDeg);  // it fell shut
  EXPECT_GT(max_violation, 0.0);    // Bullet's constraint is soft: it stretches a little
  EXPECT_LT(max_violation, 0.01);   // but holds together when nothing pulls on it
}

TEST(JointsWorld, BadJointDefinitionsAreRejectedAndTheWorldIsUnchanged) {
  World world;
  BodyId a = world.add_body(box_body(Vec3::Constant(0.05), Vec3(0, 0.05, 0), 1.0));
  BodyId b = world.add_body(box_body(Vec3::Constant(0.05), Vec3(0, 0.2, 0), 1.0));
  BodyId fixed_body = world.add_body(box_body(Vec3::Constant(0.05), Vec3(1, 0.05, 0), 0.0));
  const uint64_t hash = world.state_hash();
  auto expect_error = [&](HingeDef h, const std::string& argument, Status status) {
    try {
      world.add_joint(h);
      ADD_FAILURE() << "accepted a bad hinge: " << argument;
    } catch (const Error& e) {
      EXPECT_EQ(e.status(), status) << e.what();
      EXPECT_EQ(e.argument(), argument) << e.what();
    }
    EXPECT_EQ(world.state_hash(), hash);
    EXPECT_TRUE(world.joints().empty());
  };
  HingeDef good;
  good.parent = a;
  good.child = b;
  HingeDef h = good;
  h.axis_parent = Vec3::Zero();
  expect_error(h, "hinge.axis_parent", Status::InvalidArgument);
  h = good;
  h.lower = 1;
  h.upper = 0;
  expect_error(h, "hinge.lower", Status::InvalidArgument);
  h = good;
  h.pivot_parent.x() = NAN;
  expect_error(h, "hinge.pivot_parent", Status::InvalidArgument);
  h = good;
  h.child = a;
  expect_error(h, "hinge.child", Status::InvalidArgument);
  h = good;
  h.child = fixed_body;
  expect_error(h, "hinge.child", Status::InvalidState);
  h = good;
  h.upper = 1e308;  // beyond +-1e6 rad (any span is legal, JointsWorld.HingeLimitsWiderThanTwoPi*)
  h.lower = 0;
  expect_error(h, "hinge.upper", Status::InvalidArgument);
  h = good;
  h.parent = BodyId{77, 3};
  expect_error(h, "hinge.parent", Status::StaleId);

  JointId j = world.add_joint(good);
  const uint64_t with_joint = world.state_hash();
  HingeDef loop;
  loop.parent = b;
  loop.child = a;
  try {
    world.add_joint(loop);
    ADD_FAILURE() << "accepted a loop";
  } catch (const Error& e) {
    EXPECT_EQ(e.status(), Status::InvalidState) << e.what();
  }
  EXPECT_THROW(world.add_joint(good), Error);  // second hard joint on the same child
  EXPECT_THROW(world.remove_body(b), Error);   // a joint still uses it
  EXPECT_THROW(world.set_body_pose(b, Pose{}), Error);
  EXPECT_THROW(world.set_joint_value(j, NAN), Error);
  EXPECT_EQ(world.state_hash(), with_joint);
  world.remove_joint(j);
  EXPECT_FALSE(world.contains(j));
  EXPECT_THROW(world.joint_state(j), Error);  // stale
  world.remove_body(b);                        // free again
}

// Found by the fuzz driver (issue 22 item 2): the loop check walked hard joints only, so two soft joints each the
// other's parent were accepted and the next step hung in group_root walking the ring.
TEST(JointsWorld, SoftJointLoopsAreRefusedLikeHardOnes) {
  World world;
  BodyId a = world.add_body(box_body(Vec3::Constant(0.05), Vec3(0, 0.5, 0), 1.0));
  BodyId b = world.add_body(box_body(Vec3::Constant(0.05), Vec3(0, 0.7, 0), 1.0));
  FixedDef first;
  first.model = JointModel::Soft;
  first.parent = a;
  first.child = b;
  first.relative.position = Vec3(0, 0.2, 0);
  world.add_joint(first);
  const uint64_t with_one = world.state_hash();
  FixedDef back = first;
  back.parent = b;
  back.child = a;
  try {
    world.add_joint(back);
    ADD_FAILURE() << "accepted a ring of two soft joints";
  } catch (const Error& e) {
    EXPECT_EQ(e.argument(), "fixed.parent") << e.what();
    EXPECT_EQ(e.status(), Status::InvalidState) << e.what();
  }
  HingeDef hard_back;
  hard_back.parent = b;
  hard_back.child = a;
  EXPECT_THROW(world.add_joint(hard_back), Error);  // a hard joint closing the ring through the soft one
  EXPECT_EQ(world.state_hash(), with_one);
  for (int i = 0; i < 30; ++i) world.step(kDt);  // ends: the group has a root
  EXPECT_TRUE(world.body_pose(b).position.allFinite());
}

TEST(JointsWorld, RemovedJointLeavesAFreeBodyWithItsVelocity) {
  Pendulum p(60 * kDeg);
  for (int i = 0; i < 10; ++i) p.world.step(kDt);
  const Vec3 v = p.world.body_linear_velocity(p.rod);
  EXPECT_GT(v.norm(), 0.1);
  p.world.remove_joint(p.hinge);
  EXPECT_EQ(p.world.body_motion(p.rod), BodyMotion::Dynamic);
  p.world.step(kDt);
  EXPECT_NEAR((p.world.body_linear_velocity(p.rod) - v).norm(), 9.81 * kDt, 0.05);
}

TEST_P(JointsWorldHand, PaperPipelineOpensTheLidLikeTheLeanOne) {
  // Same hand script through both pipelines: the lean one (closed-form contacts, culling, exact solver)
  // and the paper's (Bullet particle objects, every stage every step, Ceres LM when built).
  auto run = [this](bool paper) {
    WorldDef wd = test::with_rule(GetParam());
    wd.paper_pipeline = paper;
    if (paper) wd.particle_contacts = WorldDef::ParticleContacts::BulletObjects;
    World world(wd);
    JewelryBox box = build_jewelry_box(world);
    const HandId hand = world.add_hand(HandDef{});
    bool grasped = false;
    for (int i = 0; i < 80; ++i) {
      const double angle = std::clamp((i - 20) / 60.0, 0.0, 1.0) * 60 * kDeg;
      world.step(kDt, {{hand, pinch(box, world, angle, i * kDt)}});
      grasped = grasped || world.body_grasp(box.lid).grasped;
      EXPECT_LE(world.joint_state(box.hinge).violation, 1e-9);
    }
    EXPECT_TRUE(grasped) << (paper ? "paper" : "lean");
    return world.joint_state(box.hinge).value;
  };
  const double lean = run(false), paper = run(true);
  EXPECT_NEAR(lean, 60 * kDeg, 2 * kDeg);
  EXPECT_NEAR(paper, lean, 2 * kDeg);
}

HANDSIM_BOTH_GRASP_RULES(JointsWorldHand);

// The pinch shape swinging the lid 0.5 rad about the hinge in 1 s, then held still for 0.5 s, its index pads on
// top of the lid and its thumb under the lip, both inside the lid (the tracked fingers of the pinch recordings,
// past both faces): no grasp (the hand never closes), only the physical push's overlap removal moves the lid. Its
// largest angle is the same at 30, 60 and 120 Hz within 2 deg (the judge's rate check). Before the hinge's
// balance of pushes (docs/grasp.md "Why a push depends on the frame rate"): 44.35 / 29.44 / 26.00 deg.
TEST(JointsWorld, LidPushedFromBothFacesSwingsAlikeAtEveryFrameRate) {
  std::vector<double> largest;
  for (int rate : {30, 60, 120}) {
    FixedBaseLid scene;
    World& world = scene.world;
    const JewelryBox& box = scene.box;
    const HandId hand = scene.hand;
    const double dt = 1.0 / rate;
    double most = 0, last = 0, still_jump = 0;  // still_jump: the largest change in a frame once the hand stopped
    for (int i = 0; i <= int(1.5 * rate); ++i) {
      const double swing = 0.5 * std::min(1.0, i * dt);
      const Pose palm = box.lid_pinch_palm(world, Handedness::Right, swing);
      world.step(dt, {{hand, make_hand_frame(Handedness::Right, palm, lid_pinch_shape())}});
      ASSERT_FALSE(world.body_grasp(box.lid).grasped);
      const double value = world.joint_state(box.hinge).value;
      most = std::max(most, value);
      if (i * dt > 1.0) still_jump = std::max(still_jump, std::abs(value - last));
      last = value;
    }
    std::printf("lid pushed from both faces at %d Hz: largest %.2f deg, largest change in a frame after the hand "
                "stopped %.2f deg\n", rate, most / kDeg, still_jump / kDeg);
    largest.push_back(most);
  }
  const auto [lo, hi] = std::minmax_element(largest.begin(), largest.end());
  EXPECT_LE(*hi - *lo, 2 * kDeg);
}

// A lid open at its 90 deg stop on a base sliding towards the front at 0.5 m/s, touched by the pinch shape that moves
// with the box (fingers past both faces, never closing, so only the physical push moves the lid): the lid turns as on
// a base standing still, every frame within 0.5 deg. The push's velocity solve works in the world, where the lid
// moves with its base; projected onto the hinge whole, the slide read as a turn about the hinge and the lid jumped
// between 84.4 and 87.0 deg frame to frame (87.7 on the still base). docs/grasp.md "Under Wrap": a base held by a
// jittering hand turned its lid shut.
TEST(JointsWorld, PushedLidOnAMovingBaseTurnsOnlyByItsHinge) {
  auto angles = [](const Vec3& slide) {
    WorldDef d;
    d.push_model = PushModel::Wrap;
    World world(d);
    const JewelryBox box = build_jewelry_box(world);
    const HandId hand = world.add_hand(HandDef{});
    world.set_joint_value(box.hinge, 90 * kDeg);
    std::vector<double> out;
    for (int i = 0; i < 30; ++i) {
      world.set_body_velocity(box.base, slide, Vec3::Zero());
      const Pose palm = box.lid_pinch_palm(world, Handedness::Right, 90 * kDeg);
      world.step(kDt, {{hand, make_hand_frame(Handedness::Right, palm, lid_pinch_shape())}});
      EXPECT_FALSE(world.body_grasp(box.lid).grasped);
      out.push_back(world.joint_state(box.hinge).value);
    }
    return out;
  };
  const std::vector<double> still = angles(Vec3::Zero()), sliding = angles(Vec3(0, 0, 0.5));  // the lip faces +z
  double most = 0;
  for (size_t i = 2; i < still.size(); ++i) most = std::max(most, std::abs(sliding[i] - still[i]));
  std::printf("lid on a base sliding at 0.5 m/s against a still one: largest difference %.2f deg (last %.2f vs "
              "%.2f)\n", most / kDeg, sliding.back() / kDeg, still.back() / kDeg);
  EXPECT_LE(most, 0.5 * kDeg);
}

// The pinch grasps the lid, swings it to 20 deg in 0.5 s and holds it; at 0.9 s its tracked palm jumps 5 deg further
// (one tracker jump, in one frame at any rate), and 1/30 s later the hand opens, its palm still, the thumb left under
// the lip. The jump carried the held lid and the fingers together, so nothing moved into the lid: after the release it
// rests on the thumb alike at 30 and 120 Hz. What a frame's step cannot avoid is the gravity it integrates before a
// contact answers: from rest, alpha dt^2 in one frame, and a lid's angular acceleration under its own weight is at
// most g / r (its inertia about the hinge is at least m r^2, r its centre of mass's distance from the hinge axis; 8
// deg at 30 Hz). The bound is that one 30 Hz frame's fall. With the lid's one-step velocity against the fingers'
// 0.05 s slope (moved_into before the body's path), still fingers under a lid bouncing off them read its fall as their
// own motion into it, and the lid climbed from 25 deg to 40.92 deg at 30 Hz and 28.16 at 120 Hz in 0.3 s (12.8 deg
// apart); with the path's slope ending a frame behind the fingers', it fell shut at 30 Hz (25.10 at 120 Hz). Since the
// release frame carries the lid to its hand (session 18), its first free frame starts at rest on the still thumb, and
// whether that press bore it was the sign of a rounding (-7.4e-19 m/s at 30 Hz: it fell and shut); a press from below
// leaving it at rest bears it now: 25.00 / 25.00 deg (23.51 / 25.44 before both).
// docs/grasp.md "Under Wrap" (frame rates), confidence2.
// The let-go tests below were measured with the pinch where lid_pinch_palm put it before its palm was raised 4 mm off
// the lid (kPinchLift), and reach it from above in kReachS.
constexpr double kPinchLift = -0.004, kReachS = 0.15;

TEST(JointsWorld, LidLetGoRightAfterATrackerJumpRestsAlikeAtEveryFrameRate) {
  std::vector<double> rest;
  double bound = 0;
  for (int rate : {30, 120}) {
    FixedBaseLid scene;
    World& world = scene.world;
    const JewelryBox& box = scene.box;
    const HandId hand = scene.hand;
    const double dt = 1.0 / rate, jump_at = 0.9, open_at = jump_at + 1.0 / 30;
    HandPoseParams grip = lid_pinch_shape();
    grip.curl[2] = grip.curl[3] = grip.curl[4] = 0.6;  // the fingers off the lid curled: the grasp ends as they open
    bool grasped = false, released = false;
    // The hand comes down open onto the lid from 3 cm above in kReachS (a hand that appeared on it would not be seen
    // reaching it: HandBodyPair::appeared_inside), to its pinch 4 mm below lid_pinch_palm's (where this was measured).
    for (int k = 0; k * dt < kReachS - 1e-9; ++k)
      world.step(dt, {{hand, make_hand_frame(Handedness::Right,
                                             box.lid_pinch_palm(world, Handedness::Right, 0, kPinchLift + 0.03 * (1 - k * dt / kReachS)),
                                             open_grip(grip, 1.0))}});
    for (int i = 0; i * dt < open_at + 0.3 - 1e-9; ++i) {
      const double t = i * dt;
      const double swing = 20 * kDeg * std::clamp((t - 0.3) / 0.5, 0.0, 1.0) + (t >= jump_at - 1e-9 ? 5 * kDeg : 0.0);
      const HandPoseParams shape = t < 0.3 ? closing_grip(grip, t) : t < open_at - 1e-9 ? grip : open_grip(grip, 1.0);
      world.step(dt, {{hand, make_hand_frame(Handedness::Right, box.lid_pinch_palm(world, Handedness::Right, swing, kPinchLift), shape)}});
      const bool held = world.body_grasp(box.lid).grasped;
      grasped = grasped || held;
      released = released || (grasped && !held);
      if (rate == 30 && t < open_at - 1e-9) {
        const Vec3 arm = world.body_pose(box.lid).position - box.hinge_pivot(world);
        const double r = (arm - arm.dot(box.hinge_axis(world)) * box.hinge_axis(world)).norm();
        bound = 9.81 / r * dt * dt;
      }
    }
    ASSERT_TRUE(released);
    rest.push_back(world.joint_state(box.hinge).value);
    std::printf("lid let go right after a 5 deg jump at %d Hz: %.2f deg 0.3 s after the hand opened\n", rate,
                rest.back() / kDeg);
  }
  std::printf("apart %.2f deg, bound (one 30 Hz frame's fall) %.2f deg\n", std::abs(rest[0] - rest[1]) / kDeg, bound / kDeg);
  EXPECT_LE(std::abs(rest[0] - rest[1]), bound);
  EXPECT_GT(rest[1], 20 * kDeg);  // it rests on the thumb, neither shut nor thrown
}

// The pinch grasps the lid and swings it open at 60 deg/s; at 0.9 s the hand opens and the grasp ends in the frame that
// first sees it open (0.933 s at 30 and 60 Hz, 0.942 s at 120). A grasp's end is seen only at the end of its frame,
// after the hand held the body through it, so the lid leaves from where its hand holds it at that frame's end and with
// its hand's motion over velocity_window_s (as a released free body does, Grasps::end_grasp). Before, it was freed
// where the last held frame had left it and kept the held solve's one-step rate, and in the release frame it was 0.43 /
// -3.53 / 0.01 deg behind its hand at 30 / 60 / 120 Hz, leaving at 55.8 / 58.0 / 58.9 deg/s; 0.2 s later 44.01 / 49.00
// / 47.25 deg (now 44.89 / 46.92 / 47.26, printed). confidence2's lid, lifted 5.6 deg in the last 25 ms before its
// release, reached 23.20 deg at 30 Hz and 27.95 at 120 (docs/grasp.md "Under Wrap", frame rates).
TEST(JointsWorld, LidReleasedWhileSwingingLeavesFromItsHandAtEveryFrameRate) {
  std::vector<double> behind, rates;
  const double swing_rate = 60 * kDeg, open_at = 0.9;
  for (int rate : {30, 60, 120}) {
    FixedBaseLid scene;
    World& world = scene.world;
    const JewelryBox& box = scene.box;
    const HandId hand = scene.hand;
    const double dt = 1.0 / rate;
    HandPoseParams grip = lid_pinch_shape();
    grip.curl[2] = grip.curl[3] = grip.curl[4] = 0.6;  // the fingers off the lid curled: the grasp ends as they open
    double offset = 0, at_release = -1, rate_at_release = 0, swing = 0;
    for (int i = 0; i * dt < open_at + 0.2 - 1e-9; ++i) {
      const double t = i * dt;
      swing = swing_rate * std::max(0.0, t - 0.3);
      const HandPoseParams shape = t < 0.3 ? closing_grip(grip, t) : t < open_at - 1e-9 ? grip : open_grip(grip, 1.0);
      const bool held_before = world.body_grasp(box.lid).grasped;
      const Pose palm = box.lid_pinch_palm(world, Handedness::Right, swing);
      world.step(dt, {{hand, make_hand_frame(Handedness::Right, palm, shape)}});
      const bool held = world.body_grasp(box.lid).grasped;
      if (held) offset = world.joint_state(box.hinge).value - swing;  // where the grip holds the lid against the palm
      if (held_before && !held && at_release < 0) {
        at_release = world.joint_state(box.hinge).value - offset;
        rate_at_release = world.joint_state(box.hinge).rate;
        behind.push_back(swing - at_release);
        rates.push_back(rate_at_release);
        std::printf("lid released at %d Hz at %.4f s: %.2f deg behind its hand, leaving at %.1f deg/s (hand %.1f)\n",
                    rate, t, behind.back() / kDeg, rate_at_release / kDeg, swing_rate / kDeg);
      }
    }
    ASSERT_GE(at_release, 0) << rate << " Hz: never released";
    std::printf("  at %d Hz, 0.2 s after the hand opened: lid %.2f deg\n", rate,
                world.joint_state(box.hinge).value / kDeg);
  }
  for (size_t k = 0; k < behind.size(); ++k) {
    EXPECT_LE(std::abs(behind[k]), 0.1 * kDeg);  // where its hand held it in the frame the grasp ended
    EXPECT_NEAR(rates[k], swing_rate, 0.1 * swing_rate);
  }
}

// A hand that held the lid open at its 90 deg stop (its pinch 3 deg past it, as the simulated users aim) lets go where
// it holds it: the grip opens over 8 frames and the palm stays. A held body is not pushed out of its own hand, so the
// tracked fingers are still inside the lid from the hold; under Wrap that overlap is the grip's, not a push, and the
// lid stays at its stop: nothing moved into it. Removed as one displacement in the release frame it turned the lid
// 90 -> 89.04 deg, and 87.17 once open (with the glove's noise the users' fingers were up to 15 mm deep and the lid
// fell past its balance point at 83.7 deg and shut: docs/grasp.md "Under Wrap", the let-go). The open hand that then
// turns 15 deg towards closing still pushes the lid down with it, past its balance point.
TEST(JointsWorld, LidLetGoAtItsStopStaysThereUntilTheHandPushesIt) {
  WorldDef d;
  d.push_model = PushModel::Wrap;
  World world(d);
  const JewelryBox box = build_jewelry_box(world);
  const HandId hand = world.add_hand(HandDef{});
  const double goal = 93 * kDeg;
  auto step = [&](double angle, const HandPoseParams& shape, double lift = kPinchLift) {
    world.step(kDt, {{hand, make_hand_frame(Handedness::Right, box.lid_pinch_palm(world, Handedness::Right, angle, lift), shape)}});
    return world.joint_state(box.hinge).value;
  };
  bool grasped = false;
  // Comes down open from 3 cm above (as in LidLetGoRightAfterATrackerJumpRestsAlikeAtEveryFrameRate), then closes.
  for (int k = 0; k * kDt < kReachS - 1e-9; ++k)
    step(0.0, open_grip(lid_pinch_shape(), 1.0), kPinchLift + 0.03 * (1 - k * kDt / kReachS));
  for (int i = 0; i < 20; ++i) step(0.0, closing_grip(lid_pinch_shape(), i * kDt));
  for (int i = 1; i <= 60; ++i) {
    step(goal * i / 60, lid_pinch_shape());
    grasped = grasped || world.body_grasp(box.lid).grasped;
  }
  for (int i = 0; i < 10; ++i) step(goal, lid_pinch_shape());
  ASSERT_TRUE(grasped);
  ASSERT_NEAR(world.joint_state(box.hinge).value, 90 * kDeg, 1e-9);
  double lowest = M_PI;
  for (int i = 1; i <= 28; ++i) lowest = std::min(lowest, step(goal, open_grip(lid_pinch_shape(), std::min(1.0, i / 8.0))));
  EXPECT_FALSE(world.body_grasp(box.lid).grasped);
  std::printf("lid let go at its stop: lowest %.3f deg while the hand opened and stayed\n", lowest / kDeg);
  EXPECT_NEAR(lowest, 90 * kDeg, 1e-6);
  double pushed = 0;
  for (int i = 1; i <= 20; ++i) pushed = step(goal - 15 * kDeg * i / 20, open_grip(lid_pinch_shape(), 1.0));
  EXPECT_LT(pushed, 83.7 * kDeg);  // past its balance point: it falls shut
}

// A hinge child's pose is remembered (HingePoseMemo) and made again when any number it reads changes in a bit: after
// each random change of the parent's pose, the angle (+0 and -0 included) or the hinge frame, joint_child_pose is
// hinge_child_pose's pose to the bit; unchanged, it is too.
TEST(JointsWorld, TheRememberedHingeChildPoseIsTheFormulasToTheBit) {
  std::mt19937_64 rng(25);
  std::uniform_real_distribution<double> uniform(-1, 1);
  std::uniform_int_distribution<int> pick(0, 6);
  auto unit = [&] { return Quat(uniform(rng), uniform(rng), uniform(rng), uniform(rng)).normalized(); };
  std::vector<Body> bodies(2);
  Joint j;
  j.type = JointType::Hinge;
  j.parent = 0;
  j.child = 1;
  j.hinge.axis_parent = Vec3(0, 0, 1);
  for (int t = 0; t < 5000; ++t) {
    switch (pick(rng)) {
      case 0: bodies[0].pose.position[t % 3] = uniform(rng); break;
      case 1: bodies[0].pose.orientation = unit(); break;
      case 2: j.value = t % 4 == 0 ? 0.0 : t % 4 == 1 ? -0.0 : uniform(rng); break;
      case 3: j.hinge.pivot_parent[t % 3] = uniform(rng); break;
      case 4: j.hinge.axis_parent = Vec3(uniform(rng), uniform(rng), uniform(rng)).normalized(); break;
      case 5: j.hinge.pivot_child[t % 3] = uniform(rng); break;
      default: j.hinge.rest = unit(); break;  // (or nothing changed since the last call, every other time)
    }
    for (int again = 0; again < 2; ++again) {
      const Pose memo = joint_child_pose(bodies, j), made = hinge_child_pose(j.hinge, bodies[0].pose, j.value);
      ASSERT_EQ(std::memcmp(memo.position.data(), made.position.data(), sizeof(Vec3)), 0) << "change " << t;
      ASSERT_EQ(std::memcmp(memo.orientation.coeffs().data(), made.orientation.coeffs().data(), sizeof(Quat)), 0)
          << "change " << t;
    }
  }
}
