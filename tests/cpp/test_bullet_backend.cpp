// BulletBackend's own bookkeeping, below the world: what it may skip must leave Bullet's state bit for bit as
// doing it would.
#include "bullet_backend.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstring>

using namespace handsim;

namespace {

bool same_bits(const Vec3& a, const Vec3& b) { return std::memcmp(a.data(), b.data(), sizeof(double) * 3) == 0; }

void expect_same_bits(const BackendState& a, const BackendState& b) {
  ASSERT_EQ(a.bodies.size(), b.bodies.size());
  for (size_t h = 0; h < a.bodies.size(); ++h) {
    const BackendBody &x = a.bodies[h], &y = b.bodies[h];
    EXPECT_EQ(std::memcmp(x.transform.data(), y.transform.data(), sizeof x.transform), 0) << h;
    EXPECT_EQ(std::memcmp(x.interpolation.data(), y.interpolation.data(), sizeof x.interpolation), 0) << h;
    EXPECT_TRUE(same_bits(x.linear, y.linear) && same_bits(x.angular, y.angular)) << h;
    EXPECT_TRUE(same_bits(x.interpolation_linear, y.interpolation_linear)) << h;
    EXPECT_TRUE(same_bits(x.interpolation_angular, y.interpolation_angular)) << h;
    EXPECT_EQ(x.activation, y.activation) << h;
  }
  EXPECT_EQ(a.moved_kinematic, b.moved_kinematic);
  EXPECT_EQ(a.woken, b.woken);
}

// Both tests' frames, run on two backends that each hold the lid (ids a, b): a lid turning about its hinge
// (rotated, so an unmoved save's angular velocity is not exactly zero), still from frame 3 on; Bullet steps before
// frame 4, a velocity is written before frame 5. `frame_substeps(pose)` runs the frame's four idle substeps.
template <class Substeps>
void run_lid_frames(BulletBackend& x, int a, BulletBackend& y, int b, double h, Substeps&& frame_substeps) {
  for (int frame = 0; frame < 6; ++frame) {
    const double angle = 0.1 * std::min(frame, 3);
    const Pose pose{Vec3(0, 0.07 + 0.05 * std::sin(angle), 0.05 * std::cos(angle)),
                    Quat(Eigen::AngleAxisd(angle, -Vec3::UnitX()))};
    if (frame == 4) {
      x.step(h);
      y.step(h);
    }
    if (frame == 5) {
      x.write(a, pose, Vec3(0, 0.1, 0), Vec3(0.2, 0, 0));
      y.write(b, pose, Vec3(0, 0.1, 0), Vec3(0.2, 0, 0));
    }
    frame_substeps(pose);
  }
}

}  // namespace

// A hard child placed at a frame's first idle substep and kept at the others (replace_children): idle skips the
// saves that would change nothing, and Bullet ends where moving it to the same pose at every substep leaves it --
// through frames that move it, a frame where it stays, a real step and a velocity written between them.
TEST(BulletBackend, AKeptKinematicBodyEndsWhereMovingItAgainWould) {
  WorldDef def;
  BodyDef lid;
  lid.shape = ShapeDef::box({0.09, 0.0075, 0.0675});
  const double h = def.fixed_substep;
  BulletBackend moved(def), kept(def);
  const int a = moved.add(lid, BodyMotion::Kinematic), b = kept.add(lid, BodyMotion::Kinematic);
  run_lid_frames(moved, a, kept, b, h, [&](const Pose& pose) {
    for (int i = 0; i < 4; ++i) {
      moved.idle(h);
      kept.idle(h);
      moved.move_kinematic(a, pose);
      if (i == 0)
        kept.move_kinematic(b, pose);
      else
        kept.keep_kinematic(b);
      expect_same_bits(moved.state(), kept.state());
    }
  });
}

// The same frames with the first idle's save of the lid made again by the second (resave_at_next_idle, as simulate
// asks when the children placed at the first idle substep are kept at the next): from the second idle on, Bullet
// holds what it holds when the first save is made in full -- the lid's velocities differ only between the two.
TEST(BulletBackend, AResavedKinematicBodyEndsWhereSavingItTwiceWould) {
  WorldDef def;
  BodyDef lid;
  lid.shape = ShapeDef::box({0.09, 0.0075, 0.0675});
  const double h = def.fixed_substep;
  BulletBackend saved(def), resaved(def);
  const int a = saved.add(lid, BodyMotion::Kinematic), b = resaved.add(lid, BodyMotion::Kinematic);
  run_lid_frames(saved, a, resaved, b, h, [&](const Pose& pose) {
    for (int i = 0; i < 4; ++i) {
      if (i == 0) resaved.resave_at_next_idle(b);
      saved.idle(h);
      resaved.idle(h);
      if (i > 0) expect_same_bits(saved.state(), resaved.state());
      saved.move_kinematic(a, pose);
      if (i == 0)
        resaved.move_kinematic(b, pose);
      else
        resaved.keep_kinematic(b);
    }
    // The solve's placement after the substeps: the next frame's first idle saves the move.
    const Pose solved{pose.position + Vec3(0, 0.001, 0), pose.orientation};
    saved.move_kinematic(a, solved);
    resaved.move_kinematic(b, solved);
  });
  expect_same_bits(saved.state(), resaved.state());
}
