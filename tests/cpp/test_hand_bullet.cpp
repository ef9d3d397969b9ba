// The Bullet per-particle baseline (paper mode) agrees with the closed-form contacts.
#include "bullet_particles.h"
#include "handsim/hand.h"

#include <gtest/gtest.h>

#include <map>

using namespace handsim;

namespace {

void expect_agree(const ShapeDef& shape, const Pose& pose, double tolerance) {
  HandModel m = build_hand_model(HandDef{});
  HandPoseParams p;
  p.curl = {0.2, 0.3, 0.4, 0.5, 0.6};
  HandState s;
  // The hand's palm a little below the body's centre height, so particles touch it from several sides.
  pose_hand(m, make_hand_frame(Handedness::Right, Pose{pose.position + Vec3(0.01, 0.02, 0.03), Quat::Identity()}, p), s);

  std::vector<ParticleContact> own;
  collide_particles(s.tracked_positions, m.particle_radius, shape, pose, own);
  BulletParticleCollider bullet(m.particle_count(), m.particle_radius);
  int body = bullet.add_body(shape, pose);
  std::vector<std::vector<ParticleContact>> bt;
  bullet.collide(s.tracked_positions, bt);

  std::map<int, ParticleContact> a, b;
  for (auto& c : own) a[c.particle] = c;
  for (auto& c : bt[body]) b[c.particle] = c;
  int compared = 0;
  for (auto& [i, c] : a) {
    if (c.depth < tolerance) continue;  // grazing: either side may round it out
    ASSERT_TRUE(b.count(i)) << "particle " << i << " depth " << c.depth;
    EXPECT_NEAR(b[i].depth, c.depth, tolerance) << "particle " << i;
    EXPECT_LE((b[i].normal - c.normal).norm(), 1e-3) << "particle " << i;
    ++compared;
  }
  for (auto& [i, c] : b)
    if (c.depth >= tolerance) {
      EXPECT_TRUE(a.count(i)) << "particle " << i << " only in Bullet";
    }
  EXPECT_GT(compared, 20);
}

}  // namespace

TEST(HandBullet, BoxAgrees) { expect_agree(ShapeDef::box(Vec3(0.04, 0.03, 0.05)), Pose{Vec3(0, 0.5, 0), Quat(Eigen::AngleAxisd(0.3, Vec3::UnitY()))}, 1e-5); }
TEST(HandBullet, SphereAgrees) { expect_agree(ShapeDef::sphere(0.04), Pose{Vec3(0, 0.5, 0), Quat::Identity()}, 1e-5); }
TEST(HandBullet, CapsuleAgrees) {
  expect_agree(ShapeDef::capsule(0.02, 0.04), Pose{Vec3(0, 0.5, 0), Quat(Eigen::AngleAxisd(1.2, Vec3::UnitX()))}, 1e-5);
}
