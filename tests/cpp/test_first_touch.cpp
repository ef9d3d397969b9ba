// First touch (issue 22 item 8): a hand laid onto a resting body does not fling it. With the contact skin
// (WorldDef::skin_depth, docs/grasp.md "First touch"), overlaps up to the skin's depth press the body with the
// pulp's force at the contact points instead of eq. 2's kinematic fit, so the body's support takes the press.
#include "handsim/world.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>

using namespace handsim;

namespace {

// The skin the docs give: 3 mm of pulp, 20 kPa at full compression.
WorldDef with_skin(double depth = 0.003) {
  WorldDef def;
  def.skin_depth = depth;
  return def;
}

struct Resting {
  const char* name;
  Vec3 half;
  double mass;
};
// A 12 x 1 x 12 cm, 150 g plate (the issue's) and a 4 cm, 100 g cube.
const Resting kPlate{"plate", Vec3(0.06, 0.005, 0.06), 0.15};
const Resting kCube{"cube", Vec3(0.02, 0.02, 0.02), 0.1};

struct Touch {
  double moved = 0;   // largest distance of the body's centre from where it rested (m)
  double tilted = 0;  // largest rotation from its resting orientation (rad)
};

double angle_between(const Quat& a, const Quat& b) { return Eigen::AngleAxisd(a.inverse() * b).angle(); }

// The body as a free box of its size and mass with its centre at `at`.
BodyId add_box(World& world, const Resting& body, const Vec3& at) {
  BodyDef bd;
  bd.shape = ShapeDef::box(body.half);
  bd.mass = body.mass;
  bd.pose.position = at;
  return world.add_body(bd);
}

// The palm-down right hand (palm at the identity pose is the flat hand facing -y) over the body resting on the
// ground, lowered at `speed` (m/s) from 2 cm above until the lowest particle over the body's top overlaps it by
// `rest` (m), then held there for 0.5 s. Steps at `hz`.
Touch lower_onto(const WorldDef& def, const Resting& body, double speed, double hz, double rest) {
  World world(def);
  HandDef hand_def;
  hand_def.particle_count = 1182;  // explicit: the default may change
  const HandId hand = world.add_hand(hand_def);
  const BodyId id = add_box(world, body, Vec3(0, body.half.y(), 0));
  const double dt = 1 / hz;
  for (int i = 0; i < int(0.5 * hz); ++i) world.step(dt);
  const Pose start = world.body_pose(id);
  // Where the particles over the body's top are for the palm at the origin.
  HandState state;
  const HandFrame at_origin = make_hand_frame(Handedness::Right, Pose{});
  pose_hand(world.hand_model(hand), at_origin, state);
  double lowest = 1e9;
  for (Eigen::Index p = 0; p < state.tracked_positions.cols(); ++p) {
    const Vec3 x = state.tracked_positions.col(p);
    if (std::abs(x.x()) < body.half.x() && std::abs(x.z()) < body.half.z()) lowest = std::min(lowest, x.y());
  }
  const double r = world.hand_model(hand).particle_radius;
  const double end_y = 2 * body.half.y() + r - rest - lowest;  // the palm pose's height at rest
  Touch worst;
  double y = end_y + 0.02;
  for (int i = 0; i < int(0.5 * hz) || y > end_y; ++i) {
    if (y > end_y) y = std::max(end_y, y - speed * dt);
    world.step(dt, {{hand, make_hand_frame(Handedness::Right, Pose{Vec3(0, y, 0), Quat::Identity()})}});
    const Pose now = world.body_pose(id);
    worst.moved = std::max(worst.moved, (now.position - start.position).norm());
    worst.tilted = std::max(worst.tilted, angle_between(start.orientation, now.orientation));
  }
  return worst;
}

constexpr double kDeg = M_PI / 180;

}  // namespace

// The target: lowered at up to 20 cm/s and laid on it, at 30, 60 and 120 Hz, the plate and the cube move
// <= 1 mm and turn <= 1 deg; the skin's full depth and less (1, 2, 3 mm of overlap at rest). Prints the worst case
// without the skin too, for the fit, the physical push and the default (Wrap: the lowered hand is not closing, so it
// pushes as the physical push) (docs/reliability.md "First touch" and docs/grasp.md "Push models" quote them); the
// target is asserted with the skin for every model, and without it for all but the fit: their support bears the
// press (docs/grasp.md "First touch"), so the default world meets it as it is.
TEST(FirstTouch, HandLoweredOntoARestingBodyBarelyMovesIt) {
  for (PushModel model : {PushModel::Fit, PushModel::Physical, WorldDef{}.push_model})
    for (const Resting& body : {kPlate, kCube}) {
      Touch off, on;
      for (double hz : {30.0, 60.0, 120.0})
        for (double speed : {0.05, 0.10, 0.20})
          for (double rest : {0.001, 0.002, 0.003}) {
            WorldDef bare, skin = with_skin();
            bare.push_model = skin.push_model = model;
            const Touch a = lower_onto(bare, body, speed, hz, rest);
            const Touch b = lower_onto(skin, body, speed, hz, rest);
            off = {std::max(off.moved, a.moved), std::max(off.tilted, a.tilted)};
            on = {std::max(on.moved, b.moved), std::max(on.tilted, b.tilted)};
            EXPECT_LE(b.moved, 1e-3) << body.name << " " << hz << " Hz " << speed << " m/s rest " << rest;
            EXPECT_LE(b.tilted, 1 * kDeg) << body.name << " " << hz << " Hz " << speed << " m/s rest " << rest;
            if (model == PushModel::Fit) continue;  // otherwise the support bears the press: no skin needed
            EXPECT_LE(a.moved, 1e-3) << body.name << " no skin " << hz << " Hz " << speed << " m/s rest " << rest;
            EXPECT_LE(a.tilted, 1 * kDeg) << body.name << " no skin " << hz << " Hz " << speed << " m/s rest " << rest;
          }
      std::printf("first touch, %s push, %s: worst over 27 runs without skin %.2f mm %.2f deg, with 3 mm skin "
                  "%.3f mm %.3f deg\n", model == WorldDef{}.push_model ? "default (wrap)"
                                         : model == PushModel::Fit ? "fit" : "physical", body.name, off.moved * 1e3,
                  off.tilted / kDeg, on.moved * 1e3, on.tilted / kDeg);
    }
}

// A push on purpose still pushes: the flat palm (thumb up) driven sideways at 25 cm/s into the cube slides it
// along like Step.FlatPalmPushSlidesTheCubeWithoutGrasping does without the skin, at 30, 60 and 120 Hz.
TEST(FirstTouch, PushAt25CmPerSecondStillMovesTheBody) {
  for (double hz : {30.0, 60.0, 120.0}) {
    World world(with_skin());
    const HandId hand = world.add_hand(HandDef{});
    const BodyId cube = add_box(world, kCube, Vec3(0, kCube.half.y(), 0));
    const double dt = 1 / hz, speed = 0.25;
    for (int i = 0; i < int(0.5 * hz); ++i) world.step(dt);
    for (int i = 0; i < int(1.2 * hz); ++i) {
      const Pose palm{Vec3(-0.09 + speed * i * dt, kCube.half.y(), 0.02), Quat(Eigen::AngleAxisd(M_PI / 2, Vec3::UnitZ()))};
      world.step(dt, {{hand, make_hand_frame(Handedness::Right, palm)}});
    }
    const Pose end = world.body_pose(cube);
    EXPECT_GT(end.position.x(), 0.15) << hz << " Hz: it went along";
    EXPECT_NEAR(end.position.y(), kCube.half.y(), 2e-3) << hz << " Hz";
    EXPECT_LT(angle_between(Quat::Identity(), end.orientation), 5 * kDeg) << hz << " Hz: still upright";
  }
}

// A pinch closing the thumb and index pads on a 16 mm, 50 g cube on the ground from an open hand in 0.25 s
// (closing_grip), then lifting it 9 cm at 18 cm/s, stepped at `hz`. `preshaped`: the thumb opposed from the start,
// only the curls closing (the README's pinch).
namespace {

struct Lifted {
  bool grasped = false;
  bool by_the_hand = false;
  double height = 0;  // the cube's centre at the end (m)
  double moved = 0;   // the farthest the cube's centre got from where it rested before it was grasped (m)
};

Lifted pinch_and_lift(const WorldDef& def, double hz, bool preshaped) {
  World world(def);
  const HandId hand = world.add_hand(HandDef{});
  HandPoseParams pinch;
  pinch.curl = {0.2, 0.3, 0, 0, 0};
  pinch.thumb_opposition = 1.0;
  const HandFrame shape = make_hand_frame(Handedness::Right, Pose{}, pinch);
  const Vec3 between = (shape.joints[kThumbTip].position + shape.joints[kIndexTip].position) / 2;
  const double half = 0.008;
  const BodyId cube = add_box(world, Resting{"small cube", Vec3::Constant(half), 0.05}, Vec3(0, half, 0));
  Vec3 palm = Vec3(0, half, 0) - between;
  const double dt = 1 / hz;
  const Vec3 rest = world.body_pose(cube).position;
  double moved = 0;
  for (int i = 0; i < int(0.75 * hz); ++i) {
    if (i >= int(0.25 * hz)) palm.y() += 0.18 * dt;  // lift at 18 cm/s once the pinch has closed
    HandPoseParams grip = closing_grip(pinch, i * dt);
    if (preshaped) grip.thumb_opposition = pinch.thumb_opposition;
    world.step(dt, {{hand, make_hand_frame(Handedness::Right, Pose{palm, Quat::Identity()}, grip)}});
    if (!world.body_grasp(cube).grasped) moved = std::max(moved, (world.body_pose(cube).position - rest).norm());
  }
  const GraspInfo g = world.body_grasp(cube);
  return {g.grasped, g.primary == hand, world.body_pose(cube).position.y(), moved};
}

}  // namespace

// A grasp still happens under eq. 2 (PushModel::Fit, the push the skin was added to): closing_grip's pinch, whose
// thumb opposes while it closes, grasps and lifts the cube, with the skin as without it, at 30, 60 and 120 Hz. Its
// thumb pad sweeps across the cube's face, and eq. 2's fit throws the cube up into the index, which grasps it
// (docs/grasp.md "Wrap as the default, measured" (e)): printed, how far the cube moved before the grasp.
TEST(FirstTouch, PinchStillGraspsAndLifts) {
  double moved = 0;
  for (double skin : {0.0, 0.003})
    for (double hz : {30.0, 60.0, 120.0}) {
      WorldDef def = with_skin(skin);
      def.push_model = PushModel::Fit;
      const Lifted lifted = pinch_and_lift(def, hz, false);
      EXPECT_TRUE(lifted.grasped) << "skin " << skin << ", " << hz << " Hz";
      EXPECT_TRUE(lifted.by_the_hand);
      EXPECT_GT(lifted.height, 0.08) << "skin " << skin << ", " << hz << " Hz";
      moved = std::max(moved, lifted.moved);
    }
  std::printf("closing_grip's pinch on the resting cube, fit: the cube moved up to %.3f mm before the grasp\n",
              moved * 1e3);
}

// Under PushModel::Wrap the same pinch (closing_grip, not preshaped) on the cube resting on the ground: while the hand
// closes, its digits do not displace the free body, supported or not (docs/grasp.md "A closing digit does not
// displace a free body"), so the sweeping thumb pad does not slide it out of the pinch. Nothing but the ground and
// gravity acts on the cube before the grasp, so it stays where it rests, the analytic answer, to the ground contact's
// settling (bound 0.01 mm; printed), and the pinch grasps and lifts it at 30, 60 and 120 Hz, with the skin as without
// it. It failed before the rule took in supported bodies: the pad pressed the cube along the ground, no grasp.
TEST(FirstTouch, WrapClosingPinchLeavesTheRestingCubeAndLiftsIt) {
  double moved = 0;
  for (double skin : {0.0, 0.003})
    for (double hz : {30.0, 60.0, 120.0}) {
      WorldDef def = with_skin(skin);
      def.push_model = PushModel::Wrap;
      const Lifted lifted = pinch_and_lift(def, hz, false);
      EXPECT_TRUE(lifted.grasped) << "skin " << skin << ", " << hz << " Hz";
      EXPECT_TRUE(lifted.by_the_hand);
      EXPECT_GT(lifted.height, 0.08) << "skin " << skin << ", " << hz << " Hz";
      EXPECT_LT(lifted.moved, 1e-5) << "skin " << skin << ", " << hz << " Hz";
      moved = std::max(moved, lifted.moved);
    }
  std::printf("closing_grip's pinch on the resting cube, wrap: the cube moved up to %.6f mm before the grasp\n",
              moved * 1e3);
}

// Under PushModel::Wrap, the pinch preshaped: the hand opposes its thumb while it is carried to the object and then
// closes the aperture onto it, so the thumb comes down onto the cube's side. With closing_grip's thumb, which
// opposes while it closes, the sweeping pad meets the cube's face first and, pressing at its own speed, slides the
// cube out of the pinch before the index arrives (docs/grasp.md "Wrap as the default, measured" (e)): the input, not
// the grasp decision, which this pins. Under Wrap a pinch that closes onto the cube grasps and lifts it.
TEST(FirstTouch, WrapPreshapedPinchGraspsAndLifts) {
  for (double skin : {0.0, 0.003})
    for (double hz : {30.0, 60.0, 120.0}) {
      WorldDef def = with_skin(skin);
      def.push_model = PushModel::Wrap;
      const Lifted lifted = pinch_and_lift(def, hz, true);
      EXPECT_TRUE(lifted.grasped) << "skin " << skin << ", " << hz << " Hz";
      EXPECT_TRUE(lifted.by_the_hand);
      EXPECT_GT(lifted.height, 0.08) << "skin " << skin << ", " << hz << " Hz";
    }
}

// Bad settings are refused naming the field.
TEST(FirstTouch, SkinSettingsOutsideTheirRangeAreRefused) {
  for (double bad : {-1e-3, 0.051, double(NAN)}) {
    WorldDef def;
    def.skin_depth = bad;
    EXPECT_THROW(
        try { World w(def); } catch (const Error& e) {
          EXPECT_NE(std::string(e.what()).find("world.skin_depth"), std::string::npos) << e.what();
          throw;
        },
        Error);
  }
  for (double bad : {-1.0, 2e6, double(INFINITY)}) {
    WorldDef def;
    def.skin_pressure = bad;
    EXPECT_THROW(
        try { World w(def); } catch (const Error& e) {
          EXPECT_NE(std::string(e.what()).find("world.skin_pressure"), std::string::npos) << e.what();
          throw;
        },
        Error);
  }
  for (int bad : {-1, int(PushModel::Wrap) + 1}) {
    WorldDef def;
    def.push_model = PushModel(bad);
    EXPECT_THROW(
        try { World w(def); } catch (const Error& e) {
          EXPECT_NE(std::string(e.what()).find("world.push_model"), std::string::npos) << e.what();
          throw;
        },
        Error);
  }
}

namespace {

// The flat palm (thumb up, as in PushAt25CmPerSecondStillMovesTheBody) driven along +x at `speed` into a free
// 4 cm, 100 g cube in a world without gravity or ground, from 2-3 cm short of it, for `push_s` seconds, then held
// still; the cube's speed 0.3 s after the palm stopped (it has left the palm by then). Steps at `hz`.
double pushed_speed(PushModel model, double hz, double speed, double push_s) {
  WorldDef def;
  def.gravity = Vec3::Zero();
  def.ground = false;
  def.push_model = model;
  World world(def);
  const HandId hand = world.add_hand(HandDef{});
  const BodyId cube = add_box(world, kCube, Vec3::Zero());
  const double dt = 1 / hz;
  const Quat thumb_up(Eigen::AngleAxisd(M_PI / 2, Vec3::UnitZ()));
  // Where the palm's particles facing the cube are: its pose's x where they touch the cube's -x face.
  HandState state;
  pose_hand(world.hand_model(hand), make_hand_frame(Handedness::Right, Pose{Vec3::Zero(), thumb_up}), state);
  double front = -1e9;
  for (Eigen::Index p = 0; p < state.tracked_positions.cols(); ++p) {
    const Vec3 x = state.tracked_positions.col(p);
    if (std::abs(x.y()) < kCube.half.y() && std::abs(x.z() - 0.02) < kCube.half.z()) front = std::max(front, x.x());
  }
  const double r = world.hand_model(hand).particle_radius;
  const double start = -kCube.half.x() - r - front - 0.02;
  const int pushing = int(std::lround(push_s * hz)), after = int(std::lround(0.3 * hz));
  for (int i = 1; i <= pushing + after; ++i) {
    const double x = start + speed * std::min(i, pushing) * dt;
    world.step(dt, {{hand, make_hand_frame(Handedness::Right, Pose{Vec3(x, 0, 0.02), thumb_up})}});
  }
  return world.body_linear_velocity(cube).norm();
}

}  // namespace

namespace {

// The flat palm of pushed_speed starting 1 mm into the cube's -x face, accelerating from rest along +x at `accel`
// for `push_s` seconds and then stopping dead; the cube's speed 0.3 s later (it has left the palm). Steps at `hz`.
// With the 3 mm skin of "First touch": without it the overlap's displacement put the cube a frame's lead ahead
// and the contact came and went (at 90 Hz none on 4 of the last 7 frames), which frame it ended on deciding.
double accelerated_push_speed(PushModel model, double hz, double accel, double push_s, double window_s) {
  WorldDef def;
  def.gravity = Vec3::Zero();
  def.ground = false;
  def.push_model = model;
  def.skin_depth = 0.003;  // the pulp takes the palm's small lead over the cube, so the contact holds every frame
  def.grasp.velocity_window_s = window_s;
  if (window_s == 0) def.grasp.velocity_window = 4;  // the rule before: a slope over the last 4 frames
  World world(def);
  const HandId hand = world.add_hand(HandDef{});
  const BodyId cube = add_box(world, kCube, Vec3::Zero());
  const double dt = 1 / hz;
  const Quat thumb_up(Eigen::AngleAxisd(M_PI / 2, Vec3::UnitZ()));
  HandState state;
  pose_hand(world.hand_model(hand), make_hand_frame(Handedness::Right, Pose{Vec3::Zero(), thumb_up}), state);
  double front = -1e9;
  for (Eigen::Index p = 0; p < state.tracked_positions.cols(); ++p) {
    const Vec3 x = state.tracked_positions.col(p);
    if (std::abs(x.y()) < kCube.half.y() && std::abs(x.z() - 0.02) < kCube.half.z()) front = std::max(front, x.x());
  }
  const double start = -kCube.half.x() - world.hand_model(hand).particle_radius - front + 0.001;
  const int pushing = int(std::lround(push_s * hz)), after = int(std::lround(0.3 * hz));
  for (int i = 0; i <= pushing + after; ++i) {
    const double t = std::min(i, pushing) * dt;
    world.step(dt, {{hand, make_hand_frame(Handedness::Right, Pose{Vec3(start + 0.5 * accel * t * t, 0, 0.02), thumb_up})}});
  }
  return world.body_linear_velocity(cube).norm();
}

}  // namespace

// The hand's velocity is a slope over GraspSettings::velocity_window_s seconds of palm samples, not over a count of
// frames. A palm pushing a free cube while it speeds up at 1 m/s^2 for 0.4 s and then stops leaves the cube with its
// velocity as estimated at the stop, a * (0.4 s - the slope's lag), the lag being half the window. Counted in 4
// frames (the rule before, velocity_window_s 0) the window was 100 ms at 30 Hz and 25 ms at 120 Hz: the cube left at
// 0.350 / 0.367 / 0.375 / 0.383 / 0.388 m/s at 30 / 45 / 60 / 90 / 120 Hz (printed). In seconds it is 0.05 s
// rounded up to whole frames at every rate (67 ms at 30 Hz), so the speeds may differ by the lag of half the
// slowest frame, a * (1/30 s) / 2, and no more.
TEST(FirstTouch, AcceleratingPushLeavesTheSameSpeedAtEveryFrameRate) {
  const double accel = 1.0, push_s = 0.4;
  for (PushModel model : {PushModel::Physical, PushModel::Wrap}) {
    for (double window_s : {0.0, GraspSettings{}.velocity_window_s}) {
      double lo = 1e9, hi = 0;
      for (double hz : {30.0, 45.0, 60.0, 90.0, 120.0}) {
        const double v = accelerated_push_speed(model, hz, accel, push_s, window_s);
        std::printf("%s, window %s, %.0f Hz: the cube leaves at %.4f m/s\n", model == PushModel::Wrap ? "wrap" : "physical",
                    window_s > 0 ? "0.05 s" : "4 frames", hz, v);
        lo = std::min(lo, v);
        hi = std::max(hi, v);
      }
      if (window_s == 0) {
        EXPECT_GT(hi - lo, accel * (1 / 30.0) / 2) << "the rule before: its spread is what this test is for";
      } else {
        EXPECT_LE(hi - lo, accel * (1 / 30.0) / 2) << "spread over the rates";
        EXPECT_GT(lo, 0.8 * accel * push_s) << "it was pushed";
        EXPECT_LE(hi, accel * push_s) << "not faster than the palm";
      }
    }
  }
}

// A contact keeps the face its particle entered through while the particle crosses a thin body and comes out on the
// far side, as long as its depth grew by no more than the particle's reach: its motion relative to the body in two
// frames plus a radius (keep_entry_faces). Where the world keeps the bones' history (Wrap), that motion is the
// particle's own on its bone. An index finger curling at 0.2 m/s through a static 1.5 cm plate (the jewelry box lid's
// thickness) under a still palm, stepped at 30 to 120 Hz: no frame has contacts on opposite faces at any rate. With
// the palm's rigid motion as the reach (still: a radius, 3.7 mm), a tip going 6.7 mm a 30 Hz frame outran it and the
// far face answered: 10 / 14 / 5 / 3 / 2 such frames at 30 / 45 / 60 / 90 / 120 Hz (pinch-57fps' judged lid was
// grasped at 30 Hz only so; docs/grasp.md "Why a push depends on the frame rate").
TEST(FirstTouch, FingerCurlingThroughAThinBodyKeepsItsEntryFaceAtEveryFrameRate) {
  auto tip = [](double curl) {
    HandPoseParams params;
    params.curl = {0, curl, 0, 0, 0};
    return make_hand_frame(Handedness::Right, Pose{}, params).joints[kIndexTip].position;
  };
  const double speed = 0.2, arc = 0.09, most = 0.4;  // curl 0 -> 0.4 moves the tip about 9 cm along its arc
  const double curl_s = most * arc / speed;
  for (double hz : {30.0, 45.0, 60.0, 90.0, 120.0}) {
    WorldDef def;
    def.ground = false;
    def.gravity = Vec3::Zero();
    def.push_model = PushModel::Wrap;
    World world(def);
    const HandId hand = world.add_hand(HandDef{});
    BodyDef plate;
    plate.shape = ShapeDef::box(Vec3(0.03, 0.0075, 0.03));  // thin along the tip's path there (the palm's y)
    plate.mass = 0;
    plate.pose.position = 0.5 * (tip(0.1) + tip(0.2));
    const BodyId body = world.add_body(plate);
    int opposite = 0, touching = 0;
    for (int i = 0; i <= int(std::round((curl_s + 0.2) * hz)); ++i) {
      HandPoseParams params;
      params.curl = {0, most * std::min(1.0, i / hz / curl_s), 0, 0, 0};
      world.step(1 / hz, {{hand, make_hand_frame(Handedness::Right, Pose{}, params)}});
      const std::vector<ParticleContact> contacts = world.body_contacts(body, hand);
      touching += !contacts.empty();
      bool any = false;
      for (const ParticleContact& a : contacts)
        for (const ParticleContact& b : contacts) any = any || a.normal.dot(b.normal) < -0.5;
      opposite += any;
    }
    std::printf("finger curling through a plate at %.0f Hz: %d frames touching, %d with contacts on opposite faces\n",
                hz, touching, opposite);
    EXPECT_GT(touching, 0) << hz << " Hz: the finger goes through the plate";
    EXPECT_EQ(opposite, 0) << hz << " Hz";
  }
}

// PushModel::Wrap changes only what a hand closing its grip does: the flat palm (its grip span constant) driven at
// 25 cm/s into the cube pushes it exactly as the physical push does, and pushes it along.
TEST(FirstTouch, WrapPushesAsPhysicalWhileTheHandDoesNotClose) {
  Pose end[2];
  for (PushModel model : {PushModel::Physical, PushModel::Wrap}) {
    WorldDef def;
    def.push_model = model;
    World world(def);
    const HandId hand = world.add_hand(HandDef{});
    const BodyId cube = add_box(world, kCube, Vec3(0, kCube.half.y(), 0));
    const double dt = 1 / 60.0, speed = 0.25;
    for (int i = 0; i < 30; ++i) world.step(dt);
    for (int i = 0; i < 72; ++i) {
      const Pose palm{Vec3(-0.09 + speed * i * dt, kCube.half.y(), 0.02), Quat(Eigen::AngleAxisd(M_PI / 2, Vec3::UnitZ()))};
      world.step(dt, {{hand, make_hand_frame(Handedness::Right, palm)}});
    }
    end[model == PushModel::Wrap] = world.body_pose(cube);
  }
  EXPECT_GT(end[0].position.x(), 0.15) << "it went along";
  EXPECT_EQ(end[1].position, end[0].position);
  EXPECT_EQ(end[1].orientation.coeffs(), end[0].orientation.coeffs());
}

// The same push at 30, 60 and 120 Hz leaves the body with the same speed (issue 20's frame-rate check). The palm
// at 10 cm/s stops 0.3 s after it set off (a whole number of frames at every rate), a frame or two after its first
// contact with the cube (printed: the cube is still at rest when it stops at 0.27 s). The physical push carries
// the cube at the palm's speed while they touch and leaves it with that (an inelastic push): the three speeds
// agree within 5 % of the palm's speed, the share by which one frame's contact depth can change the
// Gauss-Seidel's split between the contacts. Eq. 2's fit (printed, not asserted) gives the overlap's correction
// as velocity, so how deep the last frame overlapped, which the frame rate decides, sets what the cube keeps.
TEST(FirstTouch, PhysicalPushLeavesTheSameSpeedAtEveryFrameRate) {
  const double speed = 0.1;
  for (PushModel model : {PushModel::Fit, PushModel::Physical}) {
    double lo = 1e9, hi = 0;
    for (double hz : {30.0, 60.0, 120.0}) {
      const double v = pushed_speed(model, hz, speed, 0.3);
      std::printf("push at 10 cm/s stopping just after the touch, %s, %.0f Hz: the cube leaves at %.4f m/s\n",
                  model == PushModel::Fit ? "fit" : "physical", hz, v);
      lo = std::min(lo, v);
      hi = std::max(hi, v);
    }
    if (model == PushModel::Physical) {
      EXPECT_LE(hi - lo, 0.05 * speed) << "spread over the rates";
      EXPECT_GT(lo, 0.5 * speed) << "it was pushed";
      EXPECT_LE(hi, speed * 1.05) << "not faster than the palm";
    }
  }
}


// A hand tracked inside a resting body (a tracker picking a hand up where it already is, as the experiments' left
// hand beside the jewelry box's base): under the physical push the body's support holds it, so the overlap the
// hand appeared with is not pushed out at once (before: the whole overlap removed as one frame's displacement,
// into the ground and sideways, and Bullet threw it back up). The palm-down hand appears 8 mm deep in the top of
// a 10 x 6 x 10 cm, 500 g box on the ground and stays there for 0.5 s; at 30, 60 and 120 Hz.
TEST(FirstTouch, PhysicalPushLeavesARestingBodyAHandAppearsInside) {
  for (double hz : {30.0, 60.0, 120.0}) {
    WorldDef def;
    def.push_model = PushModel::Physical;
    World world(def);
    HandDef hand_def;
    hand_def.particle_count = 1182;
    const HandId hand = world.add_hand(hand_def);
    const Vec3 half(0.05, 0.03, 0.05);
    const BodyId id = add_box(world, Resting{"box", half, 0.5}, Vec3(0, half.y(), 0));
    const double dt = 1 / hz;
    for (int i = 0; i < int(0.5 * hz); ++i) world.step(dt);
    const Pose start = world.body_pose(id);
    HandState state;
    pose_hand(world.hand_model(hand), make_hand_frame(Handedness::Right, Pose{}), state);
    double lowest = 1e9;
    for (Eigen::Index p = 0; p < state.tracked_positions.cols(); ++p) {
      const Vec3 x = state.tracked_positions.col(p);
      if (std::abs(x.x()) < half.x() && std::abs(x.z()) < half.z()) lowest = std::min(lowest, x.y());
    }
    const double y = 2 * half.y() + world.hand_model(hand).particle_radius - 0.008 - lowest;
    double moved = 0, tilted = 0;
    int touching = 0;
    for (int i = 0; i < int(0.5 * hz); ++i) {
      world.step(dt, {{hand, make_hand_frame(Handedness::Right, Pose{Vec3(0, y, 0), Quat::Identity()})}});
      touching = std::max(touching, world.body_contact_count(id, hand));
      const Pose now = world.body_pose(id);
      moved = std::max(moved, (now.position - start.position).norm());
      tilted = std::max(tilted, angle_between(start.orientation, now.orientation));
    }
    std::printf("hand appearing 8 mm inside a resting box, physical, %.0f Hz: %d contacts, moved %.3f mm, "
                "turned %.3f deg\n", hz, touching, moved * 1e3, tilted / kDeg);
    EXPECT_GT(touching, 10) << hz << " Hz: the hand is in the box";
    EXPECT_LE(moved, 1e-3) << hz << " Hz";
    EXPECT_LE(tilted, 1 * kDeg) << hz << " Hz";
  }
}

// Under Wrap, a hand that relaxes its grip on a free body does not throw it. The simulated users' left hand holds the
// jewelry box's base with its fingers curled 30-60 mm into it (a held body is not pushed out of its own hand); when
// such a grasp ended with the base lifted off its table by the glove's jitter, that overlap was removed as one
// displacement the next frame and the base flew 50 mm and more (docs/grasp.md "Under Wrap", the let-go: close 2h's
// knocked bases). Here the same grip (the users' BASE_HOLD shape and pose) on a free 20 x 6 x 12 cm box in zero g
// closes, holds, then opens by 0.3 over 8 frames: the grasp ends with the curled fingers still inside. The box was
// moved 16.2 mm by that overlap; now only as far as the hand moves into it, at most 2 mm here.
TEST(FirstTouch, WrapRelaxedGripDoesNotThrowAFreeBody) {
  constexpr double kDt = 1.0 / 60;
  WorldDef def;
  def.push_model = PushModel::Wrap;
  def.gravity = Vec3::Zero();
  def.ground = false;
  World world(def);
  const HandId hand = world.add_hand(HandDef{Handedness::Left});
  const Vec3 half(0.1, 0.03, 0.06);
  BodyDef box;
  box.shape = ShapeDef::box(half);
  box.mass = 0.5;
  box.pose.position = Vec3(0, 0.2, 0);
  const BodyId body = world.add_body(box);
  // Palm 3.5 cm outside the box's -x face, 2 cm below its middle and 2 cm towards +z, facing +x (users.py BASE_HOLD_*).
  const Pose palm{box.pose.position + Vec3(-0.035 - half.x(), -0.02, 0.02),
                  Quat(Eigen::AngleAxisd(0.5 * M_PI, Vec3::UnitZ()))};
  HandPoseParams hold;
  hold.curl = {0.18, 0.6, 0.6, 0.6, 0.6};
  hold.thumb_opposition = 0.5;
  auto step = [&](const HandPoseParams& shape) {
    world.step(kDt, {{hand, make_hand_frame(Handedness::Left, palm, shape)}});
    return world.body_pose(body).position;
  };
  bool grasped = false;
  for (int i = 0; i < 45; ++i) {
    step(closing_grip(hold, i * kDt));
    grasped = grasped || world.body_grasp(body).grasped;
  }
  ASSERT_TRUE(grasped);
  const Vec3 held = step(hold);
  double most = 0;
  for (int i = 1; i <= 38; ++i) most = std::max(most, (step(open_grip(hold, 0.3 * std::min(1.0, i / 8.0))) - held).norm());
  EXPECT_FALSE(world.body_grasp(body).grasped);
  EXPECT_GT(world.body_contact_count(body, hand), 0);  // the curled fingers are still in it
  std::printf("free body let go by a relaxed grip: moved at most %.2f mm\n", most * 1e3);
  EXPECT_LE(most, 0.002);
}
