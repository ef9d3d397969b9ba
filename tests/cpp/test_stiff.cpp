// The user's second demand: numerical stability on stiff and extreme cases. Each case states what must
// happen; all of them also check that every state stays finite, the hinge holds (violation <= 1e-9 x scene
// size) and its limits are respected.
#include "grasp_rules.h"
#include "handsim/scenes.h"
#include "pose_fit.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <functional>
#include <random>

using namespace handsim;

namespace {

constexpr double kDt = 1.0 / 60.0;
constexpr double kDeg = M_PI / 180.0;

bool finite(const Pose& p) { return p.position.allFinite() && p.orientation.coeffs().allFinite(); }

// Every case runs with both grasp rules (grasp_rules.h); the running case's rule, for Scene.
test::GraspRule g_rule = test::GraspRule::Contacts;

// The jewelry box with one right hand, and the checks every case shares.
struct Scene {
  World world;
  JewelryBox box;
  HandId hand;
  HandId second;  // a second hand a test adds, driven by step's second frame
  double size = 1.0;  // scene scale, for the violation bound
  double max_violation = 0;
  double time = 0;  // s since the hand arrived at the lip: its pinch closes (closing_grip) over kGripClosingS

  explicit Scene(JewelryBoxDef def = {}, WorldDef wd = {}) : world(test::with_rule(g_rule, wd)) {
    box = build_jewelry_box(world, def);
    hand = world.add_hand(HandDef{});
  }

  HandFrame pinch(double angle, double lift = 0, const Vec3& offset = Vec3::Zero()) const {
    Pose palm = box.lid_pinch_palm(world, Handedness::Right, angle, lift);
    palm.position += offset;
    return make_hand_frame(Handedness::Right, palm, closing_grip(lid_pinch_shape(), time));
  }

  // frames[0] drives `hand`, frames[1] (if any) `second`; no frame: untracked.
  void step(double dt, const std::vector<HandFrame>& frames) {
    std::vector<HandInput> inputs;
    if (frames.size() > 0) inputs.push_back({hand, frames[0]});
    if (frames.size() > 1) inputs.push_back({second, frames[1]});
    world.step(dt, inputs);
    time += dt;
    check();
  }

  void check() {
    for (BodyId b : world.bodies()) {
      ASSERT_TRUE(finite(world.body_pose(b)));
      ASSERT_TRUE(world.body_linear_velocity(b).allFinite());
      ASSERT_TRUE(world.body_angular_velocity(b).allFinite());
    }
    if (!world.contains(box.hinge)) return;  // a case that removed it
    const JointState s = world.joint_state(box.hinge);
    ASSERT_TRUE(std::isfinite(s.value));
    ASSERT_GE(s.value, box.def.lower);
    ASSERT_LE(s.value, box.def.upper);
    ASSERT_LE(s.violation, 1e-9 * size);
    max_violation = std::max(max_violation, s.violation);
  }
};

// A call that must be rejected: handsim::Error with this status, its argument starting with `argument`, and the
// world exactly as before (state hash, bodies, joints).
void expect_rejected(const World& world, const std::function<void()>& call, Status status,
                     const std::string& argument) {
  const uint64_t hash = world.state_hash();
  const size_t bodies = world.bodies().size(), joints = world.joints().size();
  try {
    call();
    ADD_FAILURE() << "accepted: " << argument;
  } catch (const Error& e) {
    EXPECT_EQ(e.status(), status) << e.what();
    EXPECT_EQ(e.argument().rfind(argument, 0), 0u) << e.what();
  }
  EXPECT_EQ(world.state_hash(), hash) << argument;
  EXPECT_EQ(world.bodies().size(), bodies) << argument;
  EXPECT_EQ(world.joints().size(), joints) << argument;
}

// A lid on a hinge of one full turn (-pi..pi, no limit at shut) pinched and dragged over to 170 deg: the hand
// takes it all the way (> 150 deg), the hinge holding.
void drag_the_lid_a_full_turn_over(const WorldDef& wd) {
  JewelryBoxDef turn;
  turn.lower = -M_PI;
  turn.upper = M_PI;
  Scene t(turn, wd);
  double lowest = 0;  // the lid's lowest angle: below shut it would be in its base
  for (int i = 0; i < 125; ++i) {
    t.step(kDt, {t.pinch(170 * kDeg * std::clamp((i - 20) / 90.0, 0.0, 1.0))});
    ASSERT_LE(t.world.joint_state(t.box.hinge).violation, 1e-9);
    lowest = std::min(lowest, t.world.joint_state(t.box.hinge).value);
  }
  std::printf("%s: the lid's lowest angle %.3f deg, last %.1f deg\n",
              wd.push_model == PushModel::Wrap ? "wrap" : "fit", lowest / kDeg,
              t.world.joint_state(t.box.hinge).value / kDeg);
  // Its base stops it at shut: at most the stop's 0.5 mm slop into it at the base's front edge, 12 cm from the
  // hinge (0.24 deg); the limit -pi does not.
  EXPECT_GT(lowest, -0.25 * kDeg);
  EXPECT_GT(t.world.joint_state(t.box.hinge).value, 150 * kDeg);
}

class stiff : public testing::TestWithParam<test::GraspRule> {
 protected:
  void SetUp() override { g_rule = GetParam(); }
};

}  // namespace

TEST_P(stiff, HandTeleports1mAnd100mInOneFrame) {
  Scene s;
  // The lid is grasped; the hand jumps away. The hinge holds; the contacts vanish and the grasp ends. The hand
  // comes back open and closes its pinch again.
  for (double jump : {1.0, 100.0}) {
    s.time = 0;
    for (int i = 0; i < 20; ++i) s.step(kDt, {s.pinch(0)});
    ASSERT_TRUE(s.world.body_grasp(s.box.lid).grasped) << jump;
    for (int i = 0; i < 10; ++i) s.step(kDt, {s.pinch(0, jump)});
    EXPECT_FALSE(s.world.body_grasp(s.box.lid).grasped) << jump;
    for (int i = 0; i < 60; ++i) s.step(kDt, {s.pinch(0, jump)});  // away while the lid settles
  }
}

TEST_P(stiff, TrackingLostFor1_30_300FramesThenBack) {
  for (int lost : {1, 30, 300}) {
    Scene s;
    for (int i = 0; i < 35; ++i) s.step(kDt, {s.pinch(10 * kDeg * std::clamp((i - 15) / 20.0, 0.0, 1.0))});
    ASSERT_TRUE(s.world.body_grasp(s.box.lid).grasped);
    HandFrame gone = s.pinch(0);
    gone.joints[kPalm].valid = false;
    gone.joints[kPalm].position = Vec3::Constant(NAN);  // NaN in an invalid joint is legal
    for (int i = 0; i < lost; ++i) s.step(kDt, {gone});
    // 1 frame (17 ms) is inside the 0.2 s grace: held. 30 and 300 frames are beyond it: released.
    EXPECT_EQ(s.world.body_grasp(s.box.lid).grasped, lost * kDt <= 0.2) << lost;
    for (int i = 0; i < 30; ++i) s.step(kDt, {s.pinch(0)});
  }
}

TEST_P(stiff, BadFramesAndTimeStepsAreRejectedAndChangeNothing) {
  Scene s;
  for (int i = 0; i < 5; ++i) s.step(kDt, {s.pinch(0)});
  const uint64_t hash = s.world.state_hash();
  auto rejected = [&](double dt, HandFrame f, const std::string& argument) {
    try {
      s.world.step(dt, {{s.hand, f}});
      ADD_FAILURE() << "accepted: " << argument;
    } catch (const Error& e) {
      EXPECT_EQ(e.argument().rfind(argument, 0), 0u) << e.what();
    }
    EXPECT_EQ(s.world.state_hash(), hash) << argument;
  };
  HandFrame f = s.pinch(0);
  f.joints[kIndexTip].position.x() = NAN;
  rejected(kDt, f, "hands[0].frame.joints[10].position");
  f = s.pinch(0);
  f.joints[kIndexTip].position.y() = INFINITY;
  rejected(kDt, f, "hands[0].frame.joints[10].position");
  f = s.pinch(0);
  f.joints[kWrist].orientation = Quat(0, 0, 0, 0);
  rejected(kDt, f, "hands[0].frame.joints[1].orientation");
  f = s.pinch(0);
  f.joints[kWrist].orientation = Quat(2, 0, 0, 0);
  rejected(kDt, f, "hands[0].frame.joints[1].orientation");
  for (double dt : {0.0, -kDt, double(NAN), double(INFINITY)}) rejected(dt, s.pinch(0), "dt");
  // Slightly non-unit quaternions are normalized, not rejected.
  f = s.pinch(0);
  f.joints[kWrist].orientation.coeffs() *= 1 + 1e-7;
  s.step(kDt, {f});
}

TEST_P(stiff, ExtremeTimeSteps) {
  Scene s;
  for (int i = 0; i < 20; ++i) s.step(kDt, {s.pinch(0)});  // the pinch closes at 60 Hz first
  for (double dt : {1.0, 1e-6, 1e-6, 0.5, kDt}) {
    for (int i = 0; i < 5; ++i) s.step(dt, {s.pinch(0)});
  }
  // A 1 s frame runs at most max_substeps of physics: the lid cannot be thrown far by one huge frame.
  EXPECT_TRUE(s.world.body_grasp(s.box.lid).grasped);
}

TEST_P(stiff, MassRatio1To1000BetweenLidAndBase) {
  for (double lid_mass : {0.0005, 500.0}) {
    JewelryBoxDef def;
    def.base_mass = 0.5;
    def.lid_mass = lid_mass;
    Scene s(def);
    // With the default hinge friction the 0.5 g lid is heavily overdamped (h c / I ~ 11 per substep): it
    // must creep shut monotonically, not oscillate or blow up.
    s.world.set_joint_value(s.box.hinge, 80 * kDeg);
    double previous = 80 * kDeg;
    for (int i = 0; i < 120; ++i) {
      s.step(kDt, {});
      ASSERT_LE(s.world.joint_state(s.box.hinge).value, previous + 1e-15) << lid_mass;
      previous = s.world.joint_state(s.box.hinge).value;
    }
    EXPECT_LT(previous, 80 * kDeg) << lid_mass;
    // Without friction both fall shut within 2 s.
    JewelryBoxDef free = def;
    free.damping = 0;
    Scene f(free);
    f.world.set_joint_value(f.box.hinge, 80 * kDeg);
    for (int i = 0; i < 120; ++i) f.step(kDt, {});
    EXPECT_EQ(f.world.joint_state(f.box.hinge).value, 0.0) << lid_mass;
    for (int i = 0; i < 60; ++i) s.step(kDt, {s.pinch(30 * kDeg * std::min(1.0, i / 40.0))});
  }
}

TEST_P(stiff, LimitOverdriveAt10MetresPerSecond) {
  Scene s;
  for (int i = 0; i < 20; ++i) s.step(kDt, {s.pinch(0)});
  ASSERT_TRUE(s.world.body_grasp(s.box.lid).grasped);
  // The grasp point is ~0.2 m from the hinge; 10 m/s there is 50 rad/s: 180 degrees in ~4 frames.
  for (int round = 0; round < 5; ++round)
    for (int i = 0; i <= 8; ++i) {
      const double angle = M_PI * (i <= 4 ? i / 4.0 : (8 - i) / 4.0);
      s.step(kDt, {s.pinch(angle)});
    }
}

TEST_P(stiff, ContactsWithin1umOfTheHingeAxisAreDegenerateNotNaN) {
  // A hinge whose child's vertices all lie within 1 um of the axis: the micro-simulator cannot see the
  // rotation and must keep the previous angle.
  World world;
  BodyDef rod;
  rod.shape = ShapeDef::box(Vec3(0.1, 5e-7, 5e-7));
  rod.mass = 0.1;
  rod.pose.position = Vec3(0, 0.5, 0);
  BodyId body = world.add_body(rod);
  HingeDef h;
  h.child = body;
  h.pivot_parent = Vec3(0, 0.5, 0);
  h.axis_parent = Vec3::UnitX();
  h.axis_child = Vec3::UnitX();
  h.lower = -1;
  h.upper = 1;
  JointId j = world.add_joint(h);
  for (int i = 0; i < 60; ++i) {
    world.step(kDt);
    const JointState st = world.joint_state(j);
    ASSERT_TRUE(std::isfinite(st.value));
    ASSERT_LE(st.violation, 1e-9);
  }
}

TEST_P(stiff, HandSpawnedInsideTheBoxAndSwipingThroughAt10MetresPerSecond) {
  Scene s;
  const Vec3 centre = s.world.body_pose(s.box.base).position;
  // Spawned inside the base: pushes it out, never NaN.
  Pose palm{centre, Quat::Identity()};
  for (int i = 0; i < 30; ++i) s.step(kDt, {make_hand_frame(Handedness::Right, palm)});
  // A swipe across the lid at 10 m/s (17 cm a frame): the hinge must hold, the lid stays in its limits.
  for (int i = 0; i < 12; ++i) {
    palm.position = centre + Vec3(-1.0 + i * (10 * kDt), 0.06, 0);
    s.step(kDt, {make_hand_frame(Handedness::Right, palm)});
  }
}

TEST_P(stiff, GraspDitheringEveryFrameDoesNotFlicker) {
  Scene s;
  int events = 0;
  for (int i = 0; i < 240; ++i) {
    // Alternate between a closed pinch and a hand lifted 3 mm: contacts come and go every frame.
    s.step(kDt, {s.pinch(0, (i % 2) * 0.003)});
    for (const Event& e : s.world.events())
      events += e.type == EventType::GraspBegin || e.type == EventType::GraspEnd;
  }
  EXPECT_LE(events, 4);
}

TEST_P(stiff, SceneFarFromTheOriginAndScaled) {
  struct Case {
    Vec3 origin;
    double scale;
  };
  for (const Case& c : {Case{Vec3(0.001, 0, 0), 1}, Case{Vec3(100, 0, 100), 1}, Case{Vec3(1e4, 0, -1e4), 1}}) {
    JewelryBoxDef def;
    def.position += c.origin;
    WorldDef wd;
    Scene s(def, wd);
    s.size = std::max(1.0, c.origin.norm());
    for (int i = 0; i < 90; ++i) s.step(kDt, {s.pinch(60 * kDeg * std::clamp((i - 20) / 60.0, 0.0, 1.0))});
    EXPECT_TRUE(s.world.body_grasp(s.box.lid).grasped) << c.origin.transpose();
    EXPECT_NEAR(s.world.joint_state(s.box.hinge).value, 60 * kDeg, 3 * kDeg) << c.origin.transpose();
  }
}

TEST_P(stiff, TinyAndHugeBoxesKeepTheirHinge) {
  for (double scale : {1e-3, 1e3}) {
    JewelryBoxDef def;
    def.position *= scale;
    def.base_half_extents *= scale;
    def.lid_half_thickness *= scale;
    def.lid_overhang *= scale;
    def.table = false;
    def.base_mass = 0;
    def.damping = 0;
    WorldDef wd;
    wd.ground = false;
    Scene s(def, wd);
    s.size = std::max(1.0, scale);
    s.world.set_joint_value(s.box.hinge, 80 * kDeg);
    // Falling time grows with sqrt(size): 0.2 s for the real box, ~6 s at 1000:1.
    const int frames = int(60 * 2 * std::sqrt(std::max(1.0, scale)) / 5) + 120;
    for (int i = 0; i < frames; ++i) s.step(kDt, {});
    EXPECT_EQ(s.world.joint_state(s.box.hinge).value, 0.0) << scale;
  }
}

TEST_P(stiff, TenThousandParticles) {
  World world(test::with_rule(g_rule));
  JewelryBox box = build_jewelry_box(world);
  HandDef hd;
  hd.particle_count = 10000;
  const HandId hand = world.add_hand(hd);
  EXPECT_EQ(world.hand_model(hand).particle_count(), 10000);
  for (int i = 0; i < 80; ++i) {  // comes down onto the lid from 3 cm above in 10 frames, then as before
    const double reach = 0.03 * std::max(0.0, 1 - i / 10.0);
    const Pose palm =
        box.lid_pinch_palm(world, Handedness::Right, 45 * kDeg * std::clamp((i - 30) / 40.0, 0.0, 1.0), reach);
    world.step(kDt, {{hand, make_hand_frame(Handedness::Right, palm, closing_grip(lid_pinch_shape(), (i - 10) * kDt))}});
    ASSERT_LE(world.joint_state(box.hinge).violation, 1e-9);
  }
  EXPECT_TRUE(world.body_grasp(box.lid).grasped);
}

TEST_P(stiff, ZeroAndNegativeMassAndSize) {
  Scene s;
  for (int i = 0; i < 5; ++i) s.step(kDt, {s.pinch(0)});
  struct Case {
    const char* name;
    std::function<void(JewelryBoxDef&)> edit;
    const char* argument;
  };
  const std::vector<Case> boxes = {
      {"lid mass 0", [](JewelryBoxDef& d) { d.lid_mass = 0; }, "jewelry_box.lid_mass"},
      {"lid mass < 0", [](JewelryBoxDef& d) { d.lid_mass = -0.15; }, "jewelry_box.lid_mass"},
      {"base mass < 0", [](JewelryBoxDef& d) { d.base_mass = -0.5; }, "jewelry_box.base_mass"},
      {"base size 0", [](JewelryBoxDef& d) { d.base_half_extents.y() = 0; }, "jewelry_box.base_half_extents"},
      {"base size < 0", [](JewelryBoxDef& d) { d.base_half_extents.x() = -0.09; }, "jewelry_box.base_half_extents"},
      {"lid thickness 0", [](JewelryBoxDef& d) { d.lid_half_thickness = 0; }, "jewelry_box.lid_half_thickness"},
      {"lid thickness < 0", [](JewelryBoxDef& d) { d.lid_half_thickness = -0.0075; }, "jewelry_box.lid_half_thickness"},
  };
  for (const Case& c : boxes) {
    SCOPED_TRACE(c.name);
    JewelryBoxDef d;
    c.edit(d);
    expect_rejected(s.world, [&] { build_jewelry_box(s.world, d); }, Status::InvalidArgument, c.argument);
  }
  // The same on a single body: a negative mass, a zero or negative box or sphere.
  auto body = [](double mass, const ShapeDef& shape) {
    BodyDef d;
    d.mass = mass;
    d.shape = shape;
    d.pose.position = Vec3(0, 1.5, 0);
    return d;
  };
  const Vec3 cube(0.05, 0.05, 0.05);
  expect_rejected(s.world, [&] { s.world.add_body(body(-1, ShapeDef::box(cube))); }, Status::InvalidArgument, "body.mass");
  expect_rejected(s.world, [&] { s.world.add_body(body(1, ShapeDef::box(Vec3(0.05, 0, 0.05)))); },
                  Status::InvalidArgument, "body.shape.half_extents");
  expect_rejected(s.world, [&] { s.world.add_body(body(1, ShapeDef::box(-cube))); }, Status::InvalidArgument,
                  "body.shape.half_extents");
  expect_rejected(s.world, [&] { s.world.add_body(body(1, ShapeDef::sphere(0))); }, Status::InvalidArgument,
                  "body.shape.radius");
  expect_rejected(s.world, [&] { s.world.add_body(body(1, ShapeDef::sphere(-0.05))); }, Status::InvalidArgument,
                  "body.shape.radius");
  // Mass 0 is legal and means static: a zero-mass base is fixed to the table, and the hand still opens the lid.
  JewelryBoxDef fixed;
  fixed.base_mass = 0;
  Scene f(fixed);
  EXPECT_EQ(f.world.body_motion(f.box.base), BodyMotion::Static);
  const Pose base = f.world.body_pose(f.box.base);
  for (int i = 0; i < 80; ++i) f.step(kDt, {f.pinch(45 * kDeg * std::clamp((i - 20) / 40.0, 0.0, 1.0))});
  EXPECT_NEAR(f.world.joint_state(f.box.hinge).value, 45 * kDeg, 3 * kDeg);
  EXPECT_EQ(f.world.body_pose(f.box.base).position, base.position);
}

TEST_P(stiff, LowerAboveUpperAndOutOfRangeLimits) {
  Scene s;
  for (int i = 0; i < 5; ++i) s.step(kDt, {s.pinch(0)});
  // A second box's definition, and a hinge between two new free bodies: both rejected before anything is added.
  JewelryBoxDef inverted;
  inverted.lower = 1;
  inverted.upper = 0.5;
  expect_rejected(s.world, [&] { build_jewelry_box(s.world, inverted); }, Status::InvalidArgument,
                  "jewelry_box.lower");
  JewelryBoxDef far;
  far.upper = 1e308;  // a finite stop beyond 1e6 rad (issue 22: was accepted)
  expect_rejected(s.world, [&] { build_jewelry_box(s.world, far); }, Status::InvalidArgument, "jewelry_box.upper");
  HingeDef h;
  h.parent = s.box.base;
  h.child = s.box.lid;  // (already a hard child: checked after the limits)
  h.axis_parent = h.axis_child = Vec3::UnitX();
  h.lower = 0.2;
  h.upper = -0.2;
  expect_rejected(s.world, [&] { s.world.add_joint(h); }, Status::InvalidArgument, "hinge.lower");
  h.lower = -2e6;
  h.upper = 0;
  expect_rejected(s.world, [&] { s.world.add_joint(h); }, Status::InvalidArgument, "hinge.lower");
  SliderDef sl;
  sl.parent = s.box.base;
  sl.child = s.box.lid;
  sl.lower = 0.1;
  sl.upper = 0.0;
  expect_rejected(s.world, [&] { s.world.add_joint(sl); }, Status::InvalidArgument, "slider.lower");
  // The boundaries are legal: lower == upper locks the lid (a hand cannot open it), a span of 2 pi is one full
  // turn and the hand drags the lid all the way over (to 180 deg); wider spans: JointsWorld.HingeLimitsWider*.
  JewelryBoxDef locked;
  locked.lower = locked.upper = 0;
  Scene l(locked);
  for (int i = 0; i < 65; ++i) l.step(kDt, {l.pinch(60 * kDeg * std::clamp((i - 20) / 40.0, 0.0, 1.0))});
  EXPECT_EQ(l.world.joint_state(l.box.hinge).value, 0.0);
  drag_the_lid_a_full_turn_over({});
}

// Under the physical push a hand that presses a lid before it grasps it does not set its angle by eq. 2's fit:
// the lid with no limit below shut (-pi..pi) is stopped by its base, as a real one is, and the pinch takes it
// over as under the fit (docs/grasp.md "A jointed child is stopped by its parent").
TEST_P(stiff, LowerAboveUpperAndOutOfRangeLimitsUnderWrap) {
  WorldDef wd;
  wd.push_model = PushModel::Wrap;
  drag_the_lid_a_full_turn_over(wd);
}

TEST_P(stiff, StaleAndForeignIds) {
  Scene s;
  BodyDef cube;
  cube.shape = ShapeDef::box(Vec3(0.03, 0.03, 0.03));
  cube.pose.position = Vec3(0.3, 1.0, -0.35);
  const BodyId removed = s.world.add_body(cube);
  s.world.remove_body(removed);
  HandDef left;
  left.handedness = Handedness::Left;
  const HandId gone_hand = s.world.add_hand(left);
  s.world.remove_hand(gone_hand);
  for (int i = 0; i < 20; ++i) s.step(kDt, {s.pinch(0)});
  // The same slot taken again: the old id still names the removed body (generation check), not the new one.
  const BodyId reused = s.world.add_body(cube);
  ASSERT_EQ(reused.index, removed.index);
  // Ids from another world: a bigger one, so the indices exist there but not here.
  World other;
  JewelryBox other_box = build_jewelry_box(other);
  for (int i = 0; i < 6; ++i) other.add_body(cube);
  const BodyId foreign = other.add_body(cube);
  HingeDef hd;
  hd.child = other.add_body(cube);
  hd.axis_parent = hd.axis_child = Vec3::UnitX();
  other.add_joint(hd);
  const JointId foreign_joint = other.add_joint([&] {
    HingeDef d;
    d.child = other.add_body(cube);
    d.axis_parent = d.axis_child = Vec3::UnitX();
    return d;
  }());
  const JointId stale_joint{s.box.hinge.index, s.box.hinge.generation + 1};
  for (int i = 0; i < 5; ++i) s.step(kDt, {s.pinch(0)});
  const Status stale = Status::StaleId;
  expect_rejected(s.world, [&] { s.world.body_pose(removed); }, stale, "body");
  expect_rejected(s.world, [&] { s.world.set_body_pose(removed, Pose{}); }, stale, "body");
  expect_rejected(s.world, [&] { s.world.remove_body(removed); }, stale, "body");
  expect_rejected(s.world, [&] { s.world.set_body_velocity(foreign, Vec3::Zero(), Vec3::Zero()); }, stale, "body");
  expect_rejected(s.world, [&] { s.world.body_grasp(foreign); }, stale, "body");
  expect_rejected(s.world, [&] { s.world.body_pose(BodyId{}); }, stale, "body");
  expect_rejected(s.world, [&] { s.world.joint_state(foreign_joint); }, stale, "joint");
  expect_rejected(s.world, [&] { s.world.set_joint_value(stale_joint, 0.5); }, stale, "joint");
  expect_rejected(s.world, [&] { s.world.remove_joint(foreign_joint); }, stale, "joint");
  expect_rejected(s.world, [&] { s.world.hand_palm_pose(gone_hand); }, stale, "hand");
  expect_rejected(s.world, [&] { s.world.remove_hand(gone_hand); }, stale, "hand");
  expect_rejected(s.world, [&] {
    HingeDef d;
    d.parent = foreign;
    d.child = reused;
    d.axis_parent = d.axis_child = Vec3::UnitX();
    s.world.add_joint(d);
  }, stale, "hinge.parent");
  EXPECT_FALSE(s.world.contains(removed));
  EXPECT_FALSE(s.world.contains(foreign));
  EXPECT_FALSE(s.world.contains(foreign_joint));
  EXPECT_TRUE(s.world.contains(reused));
  (void)other_box;
  // The world goes on as if nothing happened: the hand still holds and opens the lid.
  for (int i = 0; i < 40; ++i) s.step(kDt, {s.pinch(30 * kDeg * std::min(1.0, i / 30.0))});
  EXPECT_TRUE(s.world.body_grasp(s.box.lid).grasped);
  EXPECT_NEAR(s.world.joint_state(s.box.hinge).value, 30 * kDeg, 3 * kDeg);
}

TEST_P(stiff, ZeroOneTwoAndCollinearContactsInTheEq2Solve) {
  // The object-centred pose update (eq. 2) with too few contacts to fix all 6 DOFs gets the minimal-norm
  // motion: nothing for 0 contacts, a pure translation for 1, centroid translation plus the shortest arc
  // for 2 or any number on one line (the twist about the line stays 0). Never NaN, also 10 km out.
  for (const Vec3& origin : {Vec3(0, 0, 0), Vec3(1e4, 0, -1e4)}) {
    SCOPED_TRACE(origin.transpose());
    const RigidMotion none = fit_rigid_motion({}, {});
    EXPECT_EQ(none.constrained_dofs, 0);
    EXPECT_EQ(none.apply(origin), origin);

    const Vec3 q = origin + Vec3(0.02, 0.75, -0.3), p = q + Vec3(0.001, -0.002, 0.0005);
    const RigidMotion one = fit_rigid_motion({q}, {p}, {0.002});
    EXPECT_EQ(one.constrained_dofs, 3);
    EXPECT_EQ(one.R, Mat3::Identity());
    EXPECT_LE((one.apply(q) - p).norm(), 1e-12);

    // Two contacts 4 cm apart, the pair turned 10 deg about z and moved 1 mm.
    const Mat3 turn = Eigen::AngleAxisd(10 * kDeg, Vec3::UnitZ()).toRotationMatrix();
    const Vec3 c = origin + Vec3(0, 0.8, -0.35), d(0.02, 0, 0), move(0, 0.001, 0);
    const RigidMotion two = fit_rigid_motion({c - d, c + d}, {c + move - turn * d, c + move + turn * d});
    EXPECT_EQ(two.constrained_dofs, 5);
    EXPECT_LE((two.apply(c - d) - (c + move - turn * d)).norm(), 1e-9);
    EXPECT_LE((two.apply(c + d) - (c + move + turn * d)).norm(), 1e-9);
    // Shortest arc: no twist about the segment (a point off the line turns with the segment only).
    EXPECT_LE(std::abs(rotation_vector(two.R).dot(d.normalized())), 1e-9);

    // Ten collinear contacts, unequal weights: the same as two.
    std::vector<Vec3> from, to;
    std::vector<double> w;
    for (int i = 0; i < 10; ++i) {
      const Vec3 r = d * (-1 + 2 * i / 9.0);
      from.push_back(c + r);
      to.push_back(c + move + turn * r);
      w.push_back(0.1 + 0.1 * i);
    }
    const RigidMotion line = fit_rigid_motion(from, to, w);
    EXPECT_EQ(line.constrained_dofs, 5);
    EXPECT_TRUE(line.R.allFinite() && line.t.allFinite());
    for (size_t i = 0; i < from.size(); ++i) EXPECT_LE((line.apply(from[i]) - to[i]).norm(), 1e-9);
    EXPECT_LE(std::abs(rotation_vector(line.R).dot(d.normalized())), 1e-9);
  }
}

// Both hands pinch the lid's front lip 5 cm either side of its middle; then they pull apart along the lip.
// Eq. 5: the first hand to grasp is primary and moves the object, the second is secondary and re-takes its
// relative pose every frame, so it slides instead of fighting. Pulling apart therefore moves the object with
// the primary hand only, the secondary slides off, and its grasp ends (Released). On the hinged lid the
// primary's pull along the hinge axis is not a rotation: the lid keeps its angle, both hands slide off the
// lid's sides, and the lid, let go, falls shut.
namespace {

struct TwoHands {
  Scene s;
  HandId left;
  static constexpr double left_from = 20 * kDt;  // the left hand arrives (and begins to close) 20 frames in
  explicit TwoHands(bool hinged, const WorldDef& wd) : s({}, wd) {
    HandDef l;
    l.handedness = Handedness::Left;
    left = s.world.add_hand(l);
    s.second = left;
    if (!hinged) s.world.remove_joint(s.box.hinge);
  }
  // The hands' palms: the lid pinch at `angle`, lifted by `lift`, each moved `apart` outwards along the lip.
  std::vector<HandFrame> frames(double angle, double lift, double apart) const {
    const Vec3 side = s.world.body_pose(s.box.base).orientation * Vec3::UnitX();
    const Vec3 front = s.world.body_pose(s.box.base).orientation * Vec3::UnitZ();  // away from the hinge
    std::vector<HandFrame> f;
    for (Handedness h : {Handedness::Right, Handedness::Left}) {
      const double sign = h == Handedness::Right ? 1.0 : -1.0;
      Pose palm = s.box.lid_pinch_palm(s.world, h, angle, lift);
      palm.position += sign * (0.05 + apart) * side;
      // the left hand reaches its place from 5 cm in front of it, sliding in over and under the lip, while the right
      // grasps (a hand that appeared on the lid would not be seen reaching it: HandBodyPair::appeared_inside)
      if (h == Handedness::Left && s.time < left_from) palm.position += 0.05 * (1 - s.time / left_from) * front;
      // each hand closes its pinch from the frame it arrives
      const double closing_s = h == Handedness::Right ? s.time : s.time - left_from;
      f.push_back(make_hand_frame(h, palm, closing_grip(lid_pinch_shape(), closing_s)));
    }
    return f;
  }
};

void pull_apart(const WorldDef& wd) {
  for (bool hinged : {true, false}) {
    SCOPED_TRACE(hinged ? "hinged lid" : "free lid");
    TwoHands t(hinged, wd);
    Scene& s = t.s;
    const HandId right = s.hand;
    const Vec3 rest = s.world.body_pose(s.box.lid).position;
    // The right hand grasps first, the left (reaching its place from above) joins 20 frames later.
    for (int i = 0; i < 40; ++i) s.step(kDt, t.frames(0, 0, 0));
    GraspInfo g = s.world.body_grasp(s.box.lid);
    std::printf("%s, %s lid: moved %.3f mm before both hands hold it\n",
                wd.push_model == PushModel::Wrap ? "wrap" : "fit", hinged ? "hinged" : "free",
                (s.world.body_pose(s.box.lid).position - rest).norm() * 1e3);
    ASSERT_TRUE(g.grasped);
    EXPECT_EQ(g.primary, right);
    EXPECT_EQ(g.secondary, t.left);
    // Together they lift the lid: open to 30 deg (hinged) or 30 deg about the same edge, 5 cm up (free).
    const double lift = hinged ? 0.0 : 0.05;
    for (int i = 1; i <= 40; ++i) s.step(kDt, t.frames(30 * kDeg * i / 40.0, lift * i / 40.0, 0));
    g = s.world.body_grasp(s.box.lid);
    ASSERT_TRUE(g.grasped);
    EXPECT_EQ(g.primary, right);
    EXPECT_EQ(g.secondary, t.left);
    const double held = hinged ? s.world.joint_state(s.box.hinge).value : 0.0;
    if (hinged) {
      EXPECT_NEAR(held, 30 * kDeg, 1 * kDeg);
    }
    const Pose relative = g.primary_relative;
    // Pull apart: each hand 30 cm outwards along the lip in 30 frames (0.6 m/s), then they stay there.
    int left_released = -1, right_released = -1;
    for (int i = 1; i <= 60; ++i) {
      s.step(kDt, t.frames(30 * kDeg, lift, 0.3 * std::min(1.0, i / 30.0)));
      for (const Event& e : s.world.events()) {
        if (e.type != EventType::GraspEnd || e.body != s.box.lid) continue;
        EXPECT_EQ(e.reason, EventReason::Released);
        (e.hand == right ? right_released : left_released) = i;
      }
      const GraspInfo now = s.world.body_grasp(s.box.lid);
      if (!now.grasped) continue;
      EXPECT_EQ(now.primary, right) << i;  // the secondary never takes over while the primary holds
      if (hinged) {
        // A pull along the hinge axis is no rotation about it: the lid keeps its angle while held.
        EXPECT_NEAR(s.world.joint_state(s.box.hinge).value, held, 2 * kDeg) << i;
      } else {
        // Eq. 5: the free lid follows the primary hand exactly, with the relative pose of its grasp.
        const Pose expected = s.world.hand_palm_pose(right) * relative;
        EXPECT_LE((s.world.body_pose(s.box.lid).position - expected.position).norm(), 1e-9) << i;
        EXPECT_LE(s.world.body_pose(s.box.lid).orientation.angularDistance(expected.orientation), 1e-9) << i;
      }
    }
    EXPECT_GT(left_released, 0);  // the secondary slid off the lid and let go
    if (hinged) {
      // Both hands slide off the sides of the lid (it cannot follow either); let go, it falls shut.
      EXPECT_GT(right_released, 0);
      EXPECT_FALSE(s.world.body_grasp(s.box.lid).grasped);
      EXPECT_EQ(s.world.joint_state(s.box.hinge).value, 0.0);
    } else {
      // The primary keeps the free lid all the way: it has moved 30 cm with the right hand.
      EXPECT_EQ(right_released, -1);
      EXPECT_TRUE(s.world.body_grasp(s.box.lid).grasped);
    }
  }
}

}  // namespace

TEST_P(stiff, TwoHandsPullAGraspedObjectApart) { pull_apart({}); }

// Under the physical push the free lid rests on the base, which rests on the table: the base bears the pinch's
// press as the table would, so the closing pinch takes the lid where it lies (docs/grasp.md "A resting body's
// support bears the press").
TEST_P(stiff, TwoHandsPullAGraspedObjectApartUnderWrap) {
  WorldDef wd;
  wd.push_model = PushModel::Wrap;
  pull_apart(wd);
}

HANDSIM_BOTH_GRASP_RULES(stiff);
