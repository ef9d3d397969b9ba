// The static stops' bound (static_stop.cpp, may_meet_static): held_pose makes a held body's shape points and their
// stops only where its world box may lie deeper than the slop in static geometry. The bound must never skip a stop
// deeper than that, for every shape.
#include "world_impl.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <random>

using namespace handsim;

namespace {

constexpr double kSlop = 0.0005;  // StaticStop's slop (kStaticSlop)

Body body(const ShapeDef& shape, const Pose& pose, BodyMotion motion) {
  Body b;
  b.shape = shape;
  b.prepared = prepare_shape(shape);
  b.pose = pose;
  b.declared = b.motion = motion;
  b.alive = true;
  return b;
}

}  // namespace

// Boxes, spheres, capsules and a hull posed at random over the ground and about a table (a static box whose top is
// at y = 0.37): wherever the bound says no stop can be deeper than the slop, none is; and a body carried in the air
// or resting on the ground within the slop is skipped.
TEST(StaticStop, TheWorldBoxBoundNeverSkipsAStopDeeperThanTheSlop) {
  WorldDef def;  // the ground at y = 0
  const std::vector<Body> bodies = {
      body(ShapeDef::box(Vec3(0.3, 0.02, 0.3)), {Vec3(0, 0.35, 0), Quat::Identity()}, BodyMotion::Static)};
  BodyBoxes boxes;
  boxes.update_box(bodies, 0);
  StaticStopScratch scratch;
  const std::vector<ShapeDef> shapes = {
      ShapeDef::box(Vec3(0.025, 0.025, 0.025)), ShapeDef::sphere(0.03), ShapeDef::capsule(0.02, 0.04),
      ShapeDef::convex_hull({{-0.03, 0, -0.02}, {0.03, 0, -0.02}, {-0.03, 0, 0.02}, {0.03, 0, 0.02},
                             {-0.03, 0.04, -0.02}, {0.03, 0.04, -0.02}})};
  std::mt19937 rng(25);
  std::uniform_real_distribution<double> across(-0.4, 0.4), height(-0.05, 0.45), unit(-1, 1);
  std::vector<StaticStop> stops;
  int skipped = 0, deep = 0;
  for (const ShapeDef& shape : shapes)
    for (int i = 0; i < 3000; ++i) {
      const Pose pose{Vec3(across(rng), height(rng), across(rng)),
                      Quat(unit(rng), unit(rng), unit(rng), unit(rng)).normalized()};
      const Body held = body(shape, pose, BodyMotion::Kinematic);
      static_stops(def, bodies, boxes, scratch, held, pose, stops);
      double deepest = 0;
      for (const StaticStop& s : stops) deepest = std::max(deepest, s.depth);
      deep += deepest > kSlop;
      if (may_meet_static(def, bodies, boxes, scratch, held, pose)) continue;
      ++skipped;
      EXPECT_LE(deepest, kSlop) << "shape " << int(shape.type) << " at " << pose.position.transpose();
    }
  EXPECT_GT(skipped, 3000);
  EXPECT_GT(deep, 3000);
  // A 5 cm cube carried 10 cm up, and one resting on the ground 0.3 mm in (Bullet's rest): no stop can push them.
  const ShapeDef cube = ShapeDef::box(Vec3::Constant(0.025));
  for (double y : {0.125, 0.0247}) {
    const Pose pose{Vec3(0.5, y, 0), Quat::Identity()};
    EXPECT_FALSE(may_meet_static(def, bodies, boxes, scratch, body(cube, pose, BodyMotion::Kinematic), pose)) << y;
  }
}
