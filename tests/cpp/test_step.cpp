// Algorithm 1 end to end: synthetic tracked hands pinch, lift, throw, push and hand over boxes in a World.
#include "handsim/world.h"

#include "grasp.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>

using namespace handsim;

namespace {

constexpr double kDt = 1.0 / 60;
constexpr double kHalf = 0.02;  // 4 cm cube

Pose rotation(double angle, const Vec3& axis) { return {Vec3::Zero(), Quat(Eigen::AngleAxisd(angle, axis))}; }
Pose translation(const Vec3& t) { return {t, Quat::Identity()}; }

// A pinch hand: index curled 0.4, the other fingers in a fist, the thumb part way opposed. The closure (m)
// moves the whole thumb rigidly along the thumb-to-index axis, so closing by 1 mm moves the thumb pad 1 mm.
struct Pinch {
  Handedness side = Handedness::Right;
  HandFrame base;  // palm at the identity
  Vec3 axis;       // thumb tip -> index tip, palm frame
  Pose palm_in_box;  // palm pose in the box frame: the index pad rests on the box's +x face, the thumb faces -x
  double touch = 0;  // closure at which the thumb reaches the -x face (first opposing contacts)

  // The hand holding a box at `box`; `turn` rotates the hand about the box centre (box frame) first.
  HandFrame frame(const Pose& box, double closure, const Pose& turn = Pose{}) const {
    return at_palm(box * turn * palm_in_box, closure);
  }
  HandFrame at_palm(const Pose& palm, double closure) const {
    HandFrame f = base;
    for (int j = kThumbMetacarpal; j <= kThumbTip; ++j) f.joints[j].position += closure * axis;
    for (JointPose& j : f.joints) {
      j.position = palm.transform(j.position);
      j.orientation = (palm.orientation * j.orientation).normalized();
    }
    return f;
  }
};

std::vector<ParticleContact> static_contacts(const HandModel& model, const HandFrame& f, const Pose& box) {
  HandState state;
  pose_hand(model, f, state);
  std::vector<ParticleContact> out;
  collide_particles(state.tracked_positions, model.particle_radius, ShapeDef::box(Vec3::Constant(kHalf)), box, out);
  return out;
}

bool opposing(const std::vector<ParticleContact>& contacts) {
  std::vector<Vec3> d;
  for (const ParticleContact& c : contacts) d.push_back(c.normal);
  return opposing_contacts(d);
}

// Places the pinch around a cube at the origin (box frame): the pad axis along +x, fingers pointing down
// (-y); the index pad touching the +x face by 0.5 mm; `touch` found by bisection on the thumb closure.
Pinch make_pinch(const HandModel& model) {
  Pinch p;
  p.side = model.handedness;
  HandPoseParams params;
  params.curl = {0, 0.4, 1, 1, 1};
  params.thumb_opposition = 0.2;
  p.base = make_hand_frame(p.side, Pose{}, params);
  const Vec3 thumb = p.base.joints[kThumbTip].position, index = p.base.joints[kIndexTip].position;
  p.axis = (index - thumb).normalized();
  Vec3 down = -Vec3::UnitZ();
  down = (down - down.dot(p.axis) * p.axis).normalized();
  Mat3 from, to;
  from << p.axis, down, p.axis.cross(down);
  to << Vec3::UnitX(), -Vec3::UnitY(), Vec3::UnitX().cross(-Vec3::UnitY());
  const Quat q = Quat(to * from.transpose()).normalized();
  auto at_shift = [&](double s) { return Pose{Vec3(s, 0, 0) - q * (0.5 * (thumb + index)), q}; };
  const double open = -0.08;
  double lo = -0.05, hi = 0.05;  // shift along +x that just frees the index
  for (int k = 0; k < 60; ++k) {
    p.palm_in_box = at_shift(0.5 * (lo + hi));
    (static_contacts(model, p.frame(Pose{}, open), Pose{}).empty() ? hi : lo) = 0.5 * (lo + hi);
  }
  p.palm_in_box = at_shift(hi - 0.0005);
  lo = open, hi = 0.05;
  for (int k = 0; k < 60; ++k) {
    const double mid = 0.5 * (lo + hi);
    (opposing(static_contacts(model, p.frame(Pose{}, mid), Pose{})) ? hi : lo) = mid;
  }
  p.touch = hi;
  return p;
}

BodyDef cube(const Vec3& centre) {
  BodyDef def;
  def.shape = ShapeDef::box(Vec3::Constant(kHalf));
  def.mass = 0.1;
  def.pose.position = centre;
  return def;
}

int count(const std::vector<Event>& events, EventType type) {
  int n = 0;
  for (const Event& e : events) n += e.type == type;
  return n;
}

double smoothstep(double t) { return t * t * (3 - 2 * t); }

// Signed distance of a point to the cube at `box` (negative inside).
double cube_distance(const Pose& box, const Vec3& x) {
  const Vec3 q = box.inverse_transform(x).cwiseAbs() - Vec3::Constant(kHalf);
  return q.cwiseMax(0.0).norm() + std::min(q.maxCoeff(), 0.0);
}

void expect_pose_near(const Pose& a, const Pose& b, double tol, const std::string& what) {
  EXPECT_LE((a.position - b.position).norm(), tol) << what;
  EXPECT_LE(a.orientation.angularDistance(b.orientation), tol) << what;
}

// One right hand over a 4 cm, 100 g cube resting on the ground; every event of every step is kept.
struct Scene {
  World world;
  HandId hand;
  BodyId box;
  Pinch pinch;
  Pose rest;
  std::vector<Event> log;

  explicit Scene(const WorldDef& def = {}) : world(def) {
    hand = world.add_hand(HandDef{});
    box = world.add_body(cube(Vec3(0, kHalf, 0)));
    for (int i = 0; i < 30; ++i) world.step(kDt);
    pinch = make_pinch(world.hand_model(hand));
    rest = world.body_pose(box);
  }
  double hold() const { return pinch.touch + 0.003; }
  double open() const { return pinch.touch - 0.02; }

  void step(const std::vector<HandFrame>& frames) {
    world.step(kDt, frames);
    log.insert(log.end(), world.events().begin(), world.events().end());
  }
  // Comes down from 10 cm above with the thumb open.
  void approach() {
    for (int i = 0; i <= 20; ++i)
      step({pinch.frame(translation(Vec3(0, 0.1 * (1 - i / 20.0), 0)) * rest, open())});
  }
  // Approaches, then closes the thumb to hold() over 15 frames.
  void grasp() {
    approach();
    for (int i = 1; i <= 15; ++i) step({pinch.frame(rest, open() + (hold() - open()) * i / 15.0)});
  }
  // Lifts the held cube straight up by `height` over `frames` frames; returns the last cube target.
  Pose lift(double height, int frames) {
    Pose target = rest;
    for (int i = 1; i <= frames; ++i) {
      target = translation(Vec3(0, height * smoothstep(double(i) / frames), 0)) * rest;
      step({pinch.frame(target, hold())});
    }
    return target;
  }
  // Opens the thumb at 2 mm per frame around the box pose `at`, then keeps it open; returns the frame of
  // the GraspEnd (-1: none).
  int open_hand(const Pose& at, int frames) {
    int end = -1;
    for (int i = 1; i <= frames; ++i) {
      step({pinch.frame(at, std::max(open(), hold() - 0.002 * i))});
      if (count(world.events(), EventType::GraspEnd) > 0 && end < 0) end = i;
    }
    return end;
  }
};

}  // namespace

// The synthetic pinch closes on the cube: one GraspBegin naming the hand and the cube, the cube kinematic,
// and the stored relative pose is the palm-to-cube transform of the grasp frame.
TEST(Step, PinchGraspsTheCube) {
  Scene s;
  s.grasp();
  ASSERT_EQ(count(s.log, EventType::GraspBegin), 1);
  for (const Event& e : s.log) {
    EXPECT_EQ(e.hand, s.hand);
    EXPECT_EQ(e.body, s.box);
  }
  const GraspInfo g = s.world.body_grasp(s.box);
  EXPECT_TRUE(g.grasped);
  EXPECT_EQ(g.primary, s.hand);
  EXPECT_TRUE(g.secondary.is_null());
  EXPECT_EQ(s.world.body_motion(s.box), BodyMotion::Kinematic);
  expect_pose_near(s.world.hand_palm_pose(s.hand) * g.primary_relative, s.world.body_pose(s.box), 1e-12,
                   "relative pose");
  // Grabbing did not shove the cube: it is within 2 mm of where it rested.
  EXPECT_LT((s.world.body_pose(s.box).position - s.rest.position).norm(), 0.002);
}

// Lift 30 cm and turn 90 degrees about the vertical over 1 s: the cube is palm * T_rel every frame, to 1e-9.
// Opening the thumb releases it (Released), it becomes dynamic and falls back to the ground.
TEST(Step, PinchLiftTurnAndRelease) {
  Scene s;
  s.grasp();
  ASSERT_TRUE(s.world.body_grasp(s.box).grasped);
  const Pose rel = s.world.body_grasp(s.box).primary_relative;
  Pose target;
  for (int i = 1; i <= 60; ++i) {
    const double t = smoothstep(i / 60.0);
    target = translation(Vec3(0, 0.3 * t, 0)) * s.rest * rotation(M_PI / 2 * t, Vec3::UnitY());
    s.step({s.pinch.frame(target, s.hold())});
    const Pose palm = s.world.hand_palm_pose(s.hand);
    expect_pose_near(s.world.body_pose(s.box), palm * rel, 1e-9, "frame " + std::to_string(i));
    ASSERT_TRUE(s.world.body_grasp(s.box).grasped) << "frame " << i;
  }
  const Pose lifted = s.world.body_pose(s.box);
  EXPECT_NEAR(lifted.position.y() - s.rest.position.y(), 0.3, 0.003);
  EXPECT_NEAR(lifted.orientation.angularDistance(s.rest.orientation), M_PI / 2, 0.01);
  EXPECT_EQ(count(s.log, EventType::GraspEnd), 0);

  const int end = s.open_hand(target, 20);
  ASSERT_GT(end, 0) << "opening the thumb did not release the cube";
  int ends = 0;
  for (const Event& ev : s.log)
    if (ev.type == EventType::GraspEnd) {
      ++ends;
      EXPECT_EQ(ev.reason, EventReason::Released);
      EXPECT_EQ(ev.hand, s.hand);
      EXPECT_EQ(ev.body, s.box);
    }
  EXPECT_EQ(ends, 1);
  EXPECT_FALSE(s.world.body_grasp(s.box).grasped);
  EXPECT_EQ(s.world.body_motion(s.box), BodyMotion::Dynamic);
  // Free fall from ~32 cm takes ~0.26 s; after 1.5 s it rests on the ground, flat.
  for (int i = 0; i < 90; ++i) s.step({s.pinch.frame(target, s.open())});
  EXPECT_NEAR(s.world.body_pose(s.box).position.y(), kHalf, 1e-3);
  EXPECT_EQ(count(s.log, EventType::GraspBegin), 1);
}

// Thrown: the hand moves at a constant linear velocity v (of the palm) and angular velocity w while the thumb
// opens. The released cube leaves with the velocity of its point on the hand, v + w x (x - palm), and with w,
// to 5 %. In the release frame gravity has acted for one dt on the now free cube; that is taken out.
void expect_thrown_with_hand_velocity(const Vec3& v, const Vec3& w) {
  Scene s;
  s.grasp();
  const Pose lifted = s.lift(0.25, 30);
  const Pose palm0 = lifted * s.pinch.palm_in_box;
  const Pose rel = s.world.body_grasp(s.box).primary_relative;
  int released = -1;
  Pose palm;
  for (int i = 1; i <= 30 && released < 0; ++i) {
    const double t = i * kDt;
    palm = Pose{palm0.position + v * t, (Quat(Eigen::AngleAxisd(w.norm() * t, w.normalized())) * palm0.orientation)};
    if (w.isZero()) palm.orientation = palm0.orientation;
    const double closure = i <= 6 ? s.hold() : std::max(s.open(), s.hold() - 0.002 * (i - 6));
    s.step({s.pinch.at_palm(palm, closure)});
    if (count(s.world.events(), EventType::GraspEnd) == 1) released = i;
  }
  ASSERT_GT(released, 0) << "never released";
  const Vec3 x = (palm * rel).position;
  const Vec3 expected = v + w.cross(x - palm.position);
  const Vec3 linear = s.world.body_linear_velocity(s.box) - s.world.def().gravity * kDt;
  EXPECT_LE((linear - expected).norm(), 0.05 * expected.norm()) << linear.transpose() << " vs " << expected.transpose();
  EXPECT_LE((s.world.body_angular_velocity(s.box) - w).norm(), 0.05 * std::max(w.norm(), 1e-9))
      << s.world.body_angular_velocity(s.box).transpose();
  EXPECT_EQ(s.world.body_motion(s.box), BodyMotion::Dynamic);
}

TEST(Step, ThrownLinearlyLeavesWithTheHandVelocity) {
  expect_thrown_with_hand_velocity(Vec3(1.5, 0.8, -0.5), Vec3::Zero());
}

TEST(Step, ThrownWithSpinLeavesWithThePointVelocityAndSpin) {
  expect_thrown_with_hand_velocity(Vec3(1.2, 0.5, 0.0), Vec3(0.5, 3.0, -1.0));
}

// A flat hand, palm facing +x, sweeps through the cube's place at 0.25 m/s for 1.2 s: the cube slides ahead
// of it along the ground, is never grasped, and never gets into the hand: the tracked particle spheres overlap
// it by less than their radius (the skin itself never enters), and the particles drawn (deformed) are never
// inside it.
TEST(Step, FlatPalmPushSlidesTheCubeWithoutGrasping) {
  World world;
  HandId hand = world.add_hand(HandDef{});
  BodyId box = world.add_body(cube(Vec3(0, kHalf, 0)));
  for (int i = 0; i < 30; ++i) world.step(kDt);
  const double speed = 0.25, r = world.hand_model(hand).particle_radius;
  double deepest = 0, deepest_drawn = 0;
  int grasps = 0, touching = 0;
  for (int i = 0; i < 72; ++i) {
    const Pose palm{Vec3(-0.09 + speed * i * kDt, kHalf, 0.02), Quat(Eigen::AngleAxisd(M_PI / 2, Vec3::UnitZ()))};
    const Pose before = world.body_pose(box);  // what this frame's contact pass sees
    world.step(kDt, {make_hand_frame(Handedness::Right, palm)});
    grasps += count(world.events(), EventType::GraspBegin);
    touching += world.body_contact_count(box, hand) > 0;
    const Eigen::Matrix3Xd& tracked = world.hand_particles(hand, false);
    const Eigen::Matrix3Xd& drawn = world.hand_particles(hand, true);
    for (Eigen::Index p = 0; p < tracked.cols(); ++p) {
      deepest = std::max(deepest, r - cube_distance(before, tracked.col(p)));
      deepest_drawn = std::max(deepest_drawn, -cube_distance(before, drawn.col(p)));
    }
  }
  std::printf("push: deepest tracked penetration %.2f mm (r = %.2f mm), drawn %.3g m, touching frames %d, x %.3f\n",
              deepest * 1e3, r * 1e3, deepest_drawn, touching, world.body_pose(box).position.x());
  EXPECT_EQ(grasps, 0);
  EXPECT_GT(touching, 40);
  const Pose end = world.body_pose(box);
  EXPECT_GT(end.position.x(), 0.15);  // it went along
  EXPECT_NEAR(end.position.y(), kHalf, 2e-3);
  EXPECT_LT(std::abs(end.position.z()), 0.01);
  EXPECT_LT(std::acos(std::min(1.0, (end.orientation * Vec3::UnitY()).y())), 0.05);  // still upright
  EXPECT_LT(deepest, r);  // the skin (particle centres) never enters the cube
  EXPECT_LE(deepest_drawn, 1e-9);
}

// Dithering the thumb by +-1 mm every frame around first touch for 2 s: with the default hysteresis at most
// one grasp begins and ends. Without hysteresis (1 frame each way, no release margin) the same input flickers,
// which shows that the count would catch it.
int dithering_grasp_events(const GraspSettings& grasp) {
  WorldDef def;
  def.grasp = grasp;
  Scene s(def);
  s.approach();
  for (int i = 0; i < 120; ++i) s.step({s.pinch.frame(s.rest, s.pinch.touch + (i % 2 ? 0.001 : -0.001))});
  return count(s.log, EventType::GraspBegin) + count(s.log, EventType::GraspEnd);
}

TEST(Step, DitheringAtFirstTouchDoesNotFlicker) {
  EXPECT_LE(dithering_grasp_events(GraspSettings{}), 2);
  GraspSettings none;
  none.frames_to_grasp = 1;
  none.frames_to_release = 1;
  none.release_distance = 0;
  EXPECT_GE(dithering_grasp_events(none), 40);
}
