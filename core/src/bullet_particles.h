// Paper-mode baseline narrow phase: one Bullet collision object (btSphereShape) per particle in a
// btCollisionWorld with the object shapes. Same ParticleContact records as collide_particles, in single
// precision or double, whichever btScalar the Bullet build has (HANDSIM_BULLET_DOUBLE). Used for benchmarks and agreement tests.
// No Bullet header leaks out of this file (pimpl), so tests can include it.
#pragma once

#include "handsim/hand.h"

#include <memory>
#include <vector>

namespace handsim {

class BulletParticleCollider {
 public:
  BulletParticleCollider(int particle_count, double particle_radius);
  ~BulletParticleCollider();
  BulletParticleCollider(const BulletParticleCollider&) = delete;
  BulletParticleCollider& operator=(const BulletParticleCollider&) = delete;

  // Returns the body's index (0, 1, ...). Box, Sphere, Capsule, ConvexHull, TriangleMesh.
  int add_body(const ShapeDef& shape, const Pose& pose);
  void set_body_pose(int body, const Pose& pose);

  // Moves the particles to `centres` (3 x particle_count), runs Bullet's broadphase and narrowphase, and
  // replaces out[b] with the touching particles (depth > 0) of body b, deepest point per pair, by particle.
  void collide(const Eigen::Matrix3Xd& centres, std::vector<std::vector<ParticleContact>>& out);

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace handsim
