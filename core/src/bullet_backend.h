// Free-body dynamics and object-object collision, delegated to Bullet. This header is Bullet-free on
// purpose: the core owns every body's state in double and pushes it to / pulls it from Bullet around each
// substep, so no Bullet type leaks past bullet_backend.cpp.
#pragma once

#include "handsim/world.h"

#include "joint_solvers.h"

#include <array>
#include <memory>
#include <vector>

namespace handsim {

// What Bullet keeps of a body between substeps that decides its future, in Bullet's own numbers: the
// transform and velocities, the interpolation transform and velocities a kinematic body's next velocity is
// taken from, and sleep (activation state, time at rest). Saved and restored by world_state.cpp.
struct BackendBody {
  bool used = false;  // false: a free handle
  std::array<double, 12> transform{}, interpolation{};  // basis row by row, then origin
  Vec3 linear = Vec3::Zero(), angular = Vec3::Zero();
  Vec3 interpolation_linear = Vec3::Zero(), interpolation_angular = Vec3::Zero();
  int activation = 0;
  double deactivation_time = 0;
};

struct BackendState {
  std::vector<BackendBody> bodies;  // by handle
  std::vector<int> free_handles;    // in the order add() takes them
  std::vector<int> moved_kinematic;
  bool woken = true;
};

class BulletBackend {
 public:
  explicit BulletBackend(const WorldDef& def);
  ~BulletBackend();
  BulletBackend(const BulletBackend&) = delete;
  BulletBackend& operator=(const BulletBackend&) = delete;

  // Returns a backend handle (an index, reused after remove). `handle` >= 0 puts the body there (a rebuild
  // from a BackendState: restore() then sets the free handles).
  int add(const BodyDef& def, BodyMotion motion, int handle = -1);
  void remove(int handle);
  void set_motion(int handle, BodyMotion motion, double mass);
  // Push the core's state; wakes the body.
  void write(int handle, const Pose& pose, const Vec3& linear, const Vec3& angular);
  // Move a kinematic body for the coming substep; Bullet derives its velocity from the change.
  void move_kinematic(int handle, const Pose& pose);
  // move_kinematic to the pose the last one gave, which nothing has changed since (no step, write or restore):
  // the same for Bullet, without converting the pose again, and idle may skip its unchanged save.
  void keep_kinematic(int handle);
  // The coming idle's save of this kinematic body (its velocity over the substep, saveKinematicState) is made
  // again by the idle after it, and nothing between reads what the first writes (no step, write or read of it;
  // the body moved or kept before the second): the second overwrites the first's velocities and starts from the
  // transform the first leaves, so the coming idle only sets that transform. For the coming idle only.
  void resave_at_next_idle(int handle);
  void read(int handle, Pose& pose, Vec3& linear, Vec3& angular) const;
  // Whether Bullet still simulates a dynamic body; false once it has fallen asleep (at rest for Bullet's
  // deactivation time), until something wakes it (a write, a contact with a moving body).
  bool awake(int handle) const;
  // Whether anything was written (pose, velocity, motion, body or constraint added) since the last
  // step or idle: then the next substep must run Bullet even if every dynamic body sleeps.
  bool woken() const;
  void step(double h);
  // A substep in which no dynamic body is awake and nothing moving comes near one: Bullet would change no
  // dynamic body, so it is skipped. Only the bookkeeping a real step does for kinematic bodies is done
  // (their velocity over the substep), so a later real step does not see a whole pause as one jump.
  void idle(double h);

  // Soft joints (the JointModel::Soft baseline): Bullet constraints between two body handles, -1 for the
  // world. Each returns a constraint handle.
  int add_hinge(int parent, int child, const HingeFrame& f);
  int add_slider(int parent, int child, const SliderFrame& f);
  int add_ball(int parent, int child, const BallFrame& f);
  int add_fixed(int parent, int child, const FixedFrame& f);
  void remove_constraint(int handle);
  // Whether two bodies may collide. A hard joint's child overlaps its parent at the joint by design.
  void set_collision(int a, int b, bool enabled);

  // Save and restore. A backend rebuilt with add(def, motion, handle) for every used handle, its constraints
  // and collision exceptions re-added, then restore(state), is the same for every world that does so from
  // the same state; Bullet's contact caches (manifolds, broadphase pairs) start empty (docs/design.md).
  BackendState state() const;
  void restore(const BackendState& state);

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace handsim
