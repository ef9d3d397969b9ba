// The World: bodies, hands and joints, stepped frame by frame (Algorithm 1 of Kim & Park).
// Settings structs with defaults ("defs") describe what to create; the world returns opaque ids.
#pragma once

#include "handsim/shape.h"
#include "handsim/types.h"

#include <memory>
#include <vector>

namespace handsim {

struct WorldDef {
  Vec3 gravity = Vec3(0, -9.81, 0);
  // Physics runs at a fixed substep so results do not depend on the caller's frame rate; a frame's dt is
  // accumulated and consumed in whole substeps (at most max_substeps per step, the rest is dropped so a
  // long hitch cannot make the next frame explode in cost).
  double fixed_substep = 1.0 / 240.0;
  int max_substeps = 8;
  bool ground = true;  // an infinite static plane y = ground_height
  double ground_height = 0.0;
  double ground_friction = 0.5;
};

struct BodyDef {
  ShapeDef shape;
  double mass = 1.0;  // kg; 0 makes a static body
  Pose pose;
  Vec3 linear_velocity = Vec3::Zero();
  Vec3 angular_velocity = Vec3::Zero();  // rad/s, world frame
  double friction = 0.5;
  double restitution = 0.0;
  bool kinematic = false;  // moved only by set_body_pose / the hand, never by forces
};

enum class BodyMotion : int { Static = 0, Dynamic = 1, Kinematic = 2 };

class World {
 public:
  explicit World(const WorldDef& def = {});
  ~World();
  World(World&&) noexcept;
  World& operator=(World&&) noexcept;
  World(const World&) = delete;
  World& operator=(const World&) = delete;

  const WorldDef& def() const;
  // Removes every body and resets time; the WorldDef is kept.
  void reset();

  // --- bodies ---
  BodyId add_body(const BodyDef& def);
  void remove_body(BodyId id);
  bool contains(BodyId id) const;
  std::vector<BodyId> bodies() const;
  const ShapeDef& body_shape(BodyId id) const;
  double body_mass(BodyId id) const;
  BodyMotion body_motion(BodyId id) const;

  Pose body_pose(BodyId id) const;
  void set_body_pose(BodyId id, const Pose& pose);  // teleport; velocities are kept
  Vec3 body_linear_velocity(BodyId id) const;
  Vec3 body_angular_velocity(BodyId id) const;
  void set_body_velocity(BodyId id, const Vec3& linear, const Vec3& angular);

  // --- stepping ---
  void step(double dt);
  double time() const;

  // A stable 64-bit FNV-1a hash of every body's state (bits of the doubles), identical across runs and
  // processes for the same inputs.
  uint64_t state_hash() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace handsim
