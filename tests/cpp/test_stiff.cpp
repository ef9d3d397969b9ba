// The user's second demand: numerical stability on stiff and extreme cases. Each case states what must
// happen; all of them also check that every state stays finite, the hinge holds (violation <= 1e-9 x scene
// size) and its limits are respected.
#include "handsim/scenes.h"

#include <gtest/gtest.h>

#include <cmath>
#include <functional>
#include <random>

using namespace handsim;

namespace {

constexpr double kDt = 1.0 / 60.0;
constexpr double kDeg = M_PI / 180.0;

bool finite(const Pose& p) { return p.position.allFinite() && p.orientation.coeffs().allFinite(); }

// The jewelry box with one right hand, and the checks every case shares.
struct Scene {
  World world;
  JewelryBox box;
  HandId hand;
  double size = 1.0;  // scene scale, for the violation bound
  double max_violation = 0;

  explicit Scene(JewelryBoxDef def = {}, WorldDef wd = {}) : world(wd) {
    box = build_jewelry_box(world, def);
    hand = world.add_hand(HandDef{});
  }

  HandFrame pinch(double angle, double lift = 0, const Vec3& offset = Vec3::Zero()) const {
    Pose palm = box.lid_pinch_palm(world, Handedness::Right, angle, lift);
    palm.position += offset;
    return make_hand_frame(Handedness::Right, palm, lid_pinch_shape());
  }

  void step(double dt, const std::vector<HandFrame>& frames) {
    world.step(dt, frames);
    check();
  }

  void check() {
    for (BodyId b : world.bodies()) {
      ASSERT_TRUE(finite(world.body_pose(b)));
      ASSERT_TRUE(world.body_linear_velocity(b).allFinite());
      ASSERT_TRUE(world.body_angular_velocity(b).allFinite());
    }
    const JointState s = world.joint_state(box.hinge);
    ASSERT_TRUE(std::isfinite(s.value));
    ASSERT_GE(s.value, box.def.lower);
    ASSERT_LE(s.value, box.def.upper);
    ASSERT_LE(s.violation, 1e-9 * size);
    max_violation = std::max(max_violation, s.violation);
  }
};

}  // namespace

TEST(stiff, HandTeleports1mAnd100mInOneFrame) {
  Scene s;
  for (int i = 0; i < 20; ++i) s.step(kDt, {s.pinch(0)});
  ASSERT_TRUE(s.world.body_grasp(s.box.lid).grasped);
  // The lid is grasped; the hand jumps away. The hinge holds; the contacts vanish and the grasp ends.
  for (double jump : {1.0, 100.0}) {
    for (int i = 0; i < 10; ++i) s.step(kDt, {s.pinch(0, jump)});
    EXPECT_FALSE(s.world.body_grasp(s.box.lid).grasped) << jump;
    for (int i = 0; i < 20; ++i) s.step(kDt, {s.pinch(0)});
  }
}

TEST(stiff, TrackingLostFor1_30_300FramesThenBack) {
  for (int lost : {1, 30, 300}) {
    Scene s;
    for (int i = 0; i < 20; ++i) s.step(kDt, {s.pinch(10 * kDeg * std::min(1.0, i / 20.0))});
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

TEST(stiff, BadFramesAndTimeStepsAreRejectedAndChangeNothing) {
  Scene s;
  for (int i = 0; i < 5; ++i) s.step(kDt, {s.pinch(0)});
  const uint64_t hash = s.world.state_hash();
  auto rejected = [&](double dt, HandFrame f, const std::string& argument) {
    try {
      s.world.step(dt, {f});
      ADD_FAILURE() << "accepted: " << argument;
    } catch (const Error& e) {
      EXPECT_EQ(e.argument().rfind(argument, 0), 0u) << e.what();
    }
    EXPECT_EQ(s.world.state_hash(), hash) << argument;
  };
  HandFrame f = s.pinch(0);
  f.joints[kIndexTip].position.x() = NAN;
  rejected(kDt, f, "hands[0].joints[10].position");
  f = s.pinch(0);
  f.joints[kIndexTip].position.y() = INFINITY;
  rejected(kDt, f, "hands[0].joints[10].position");
  f = s.pinch(0);
  f.joints[kWrist].orientation = Quat(0, 0, 0, 0);
  rejected(kDt, f, "hands[0].joints[1].orientation");
  f = s.pinch(0);
  f.joints[kWrist].orientation = Quat(2, 0, 0, 0);
  rejected(kDt, f, "hands[0].joints[1].orientation");
  for (double dt : {0.0, -kDt, double(NAN), double(INFINITY)}) rejected(dt, s.pinch(0), "dt");
  // Slightly non-unit quaternions are normalized, not rejected.
  f = s.pinch(0);
  f.joints[kWrist].orientation.coeffs() *= 1 + 1e-7;
  s.step(kDt, {f});
}

TEST(stiff, ExtremeTimeSteps) {
  Scene s;
  for (double dt : {1.0, 1e-6, 1e-6, 0.5, kDt}) {
    for (int i = 0; i < 5; ++i) s.step(dt, {s.pinch(0)});
  }
  // A 1 s frame runs at most max_substeps of physics: the lid cannot be thrown far by one huge frame.
  EXPECT_TRUE(s.world.body_grasp(s.box.lid).grasped);
}

TEST(stiff, MassRatio1To1000BetweenLidAndBase) {
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

TEST(stiff, LimitOverdriveAt10MetresPerSecond) {
  Scene s;
  for (int i = 0; i < 15; ++i) s.step(kDt, {s.pinch(0)});
  ASSERT_TRUE(s.world.body_grasp(s.box.lid).grasped);
  // The grasp point is ~0.2 m from the hinge; 10 m/s there is 50 rad/s: 180 degrees in ~4 frames.
  for (int round = 0; round < 5; ++round)
    for (int i = 0; i <= 8; ++i) {
      const double angle = M_PI * (i <= 4 ? i / 4.0 : (8 - i) / 4.0);
      s.step(kDt, {s.pinch(angle)});
    }
}

TEST(stiff, ContactsWithin1umOfTheHingeAxisAreDegenerateNotNaN) {
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

TEST(stiff, HandSpawnedInsideTheBoxAndSwipingThroughAt10MetresPerSecond) {
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

TEST(stiff, GraspDitheringEveryFrameDoesNotFlicker) {
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

TEST(stiff, SceneFarFromTheOriginAndScaled) {
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
    for (int i = 0; i < 90; ++i) s.step(kDt, {s.pinch(60 * kDeg * std::clamp((i - 15) / 60.0, 0.0, 1.0))});
    EXPECT_TRUE(s.world.body_grasp(s.box.lid).grasped) << c.origin.transpose();
    EXPECT_NEAR(s.world.joint_state(s.box.hinge).value, 60 * kDeg, 3 * kDeg) << c.origin.transpose();
  }
}

TEST(stiff, TinyAndHugeBoxesKeepTheirHinge) {
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

TEST(stiff, TenThousandParticles) {
  World world;
  JewelryBox box = build_jewelry_box(world);
  HandDef hd;
  hd.particle_count = 10000;
  world.add_hand(hd);
  EXPECT_EQ(world.hand_model(world.hands()[0]).particle_count(), 10000);
  for (int i = 0; i < 60; ++i) {
    const Pose palm = box.lid_pinch_palm(world, Handedness::Right, 45 * kDeg * std::clamp((i - 10) / 40.0, 0.0, 1.0));
    world.step(kDt, {make_hand_frame(Handedness::Right, palm, lid_pinch_shape())});
    ASSERT_LE(world.joint_state(box.hinge).violation, 1e-9);
  }
  EXPECT_TRUE(world.body_grasp(box.lid).grasped);
}
