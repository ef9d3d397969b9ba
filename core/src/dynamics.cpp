// The dynamics stage (Algorithm 1, line 18): Bullet for the free bodies in fixed substeps, the held bodies
// gliding towards their hand across them, the hard joints integrated after each.
#include "world_impl.h"

#include <algorithm>
#include <cmath>

namespace handsim {
namespace {

// Substep i of n (h seconds each); Bullet runs only when `physics` (physics_needed), else it idles. `placed`:
// the hard children stay where the first substep placed them (simulate says when).
void substep(const WorldModel& model, WorldState& state, std::vector<Body>& bodies, std::vector<Joint>& joints,
             const std::vector<HandSlot>& hands, BulletBackend& backend, const std::vector<uint32_t>& held,
             const std::vector<uint32_t>& dynamic, BodyBoxes& boxes, double h, int i, int n, bool physics,
             bool placed) {
  // Kinematic bodies glide from the pose Bullet last saw to their target over the frame's substeps, so
  // Bullet derives the right velocity for pushing free bodies. (Declared kinematic bodies only move through
  // set_body_pose, which syncs them; the held ones are the gliders.)
  const double s = double(i + 1) / n;
  for (uint32_t bi : held) {
    Body& b = bodies[bi];
    if (b.motion != BodyMotion::Kinematic || b.jointed()) continue;
    if (!physics && i + 1 < n) continue;  // nothing sees the glide; only where it ends
    Pose p{b.synced_pose.position + s * (b.pose.position - b.synced_pose.position),
           b.synced_pose.orientation.slerp(s, b.pose.orientation)};
    backend.move_kinematic(b.backend, i + 1 == n ? b.pose : p);
  }
  drive_soft_children(held, bodies, hands, backend, h);
  if (physics) {
    backend.step(h);
    read_dynamic_bodies(state, bodies, backend, dynamic, boxes);
  } else {
    // With the children placed at this substep and kept at the next (`placed`), the next idle saves each of them
    // again before anything reads Bullet's copy: this one's save of them would be overwritten (a held lid, moved
    // by the last frame's joint solve, saved twice a frame).
    if (placed && i == 0 && n > 1) resave_children(model, joints, bodies, backend);
    backend.idle(h);
    ++state.idle_substeps;
  }
  if (placed && i > 0) {
    replace_children(model, joints, bodies, backend);
  } else if (!model.joint_order.empty()) {
    integrate_joints(model, joints, bodies, h);
    place_children(model, joints, bodies, backend);  // after the parents moved, so a child rides on a falling or carried parent
  }
}

}  // namespace

StageReport simulate(const WorldModel& model, WorldState& state, std::vector<Body>& bodies, std::vector<Joint>& joints,
                     const std::vector<HandSlot>& hands, BulletBackend& backend, const std::vector<uint32_t>& held,
                     const std::vector<uint32_t>& dynamic, BodyBoxes& boxes, StepReport& report, double dt) {
  const double h = model.def.fixed_substep;
  state.accumulator += dt;
  // The small tolerance keeps dt = 4h from yielding 3 substeps through rounding.
  int n = int(std::floor(state.accumulator / h + 1e-9));
  if (n > model.def.max_substeps) {
    n = model.def.max_substeps;
    report.dropped_seconds = state.accumulator - n * h;
    report.warnings |= warning_bit(StepWarning::SubstepsDropped);
    state.accumulator = n * h;  // drop what cannot be caught up
  }
  const bool physics = n > 0 && physics_needed(model, state, bodies, joints, backend, held, dynamic, boxes, dt);
  // Idle, the substeps move a body only through place_children (Bullet's bodies are not read back, a held body
  // glides in Bullet's copy alone, a soft child's velocity is the same each substep); with no hard joint
  // integrated either, nothing place_children reads changes after the first substep, so the later ones would
  // place every child exactly where the first did (a held lid on a fixed base).
  const bool placed = !physics && !model.joint_order.empty() && !joints_integrate(model, joints, bodies);
  for (int i = 0; i < n; ++i)
    substep(model, state, bodies, joints, hands, backend, held, dynamic, boxes, h, i, n, physics, placed);
  state.accumulator = std::max(0.0, state.accumulator - n * h);
  if (n > 0)
    for (uint32_t bi : held)
      if (bodies[bi].motion == BodyMotion::Kinematic && !bodies[bi].jointed()) bodies[bi].synced_pose = bodies[bi].pose;
  report.substeps = n;
  report.bullet = physics;
  if (n == 0) return stage_skipped(SkipReason::BelowSubstep);
  return stage_work(n);
}

}  // namespace handsim
