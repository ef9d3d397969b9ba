// One frame: Algorithm 1 of Kim & Park, read top-down in World::step. Each stage, its math and the glue that
// runs it over the world's hands and bodies, lives in the file named after it (skinning, contacts,
// deformation, grasp, pose_fit, world_joints); this file holds the step itself, its input check and the
// dynamics stage (line 18: Bullet in fixed substeps).
#include "validate.h"
#include "world_impl.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <string>

namespace handsim {

StepReport World::step(double dt, const std::vector<HandInput>& hands) {
  const auto held = lock();
  return impl_->step(dt, impl_->frames_by_id(dt, hands));  // nothing runs on bad input: the world stays intact
}

StepReport World::step(double dt, const std::vector<HandFrame>& hands) {
  const auto held = lock();
  return impl_->step(dt, impl_->frames_by_position(dt, hands));
}

StepReport World::Impl::step(double dt, const SlotFrames& frames) {
  Impl& w = *this;
  w.events.erase(w.events.begin(), w.events.begin() + std::ptrdiff_t(std::min(w.step_events, w.events.size())));
  w.report = StepReport();
  for (Joint& j : w.joints) j.clear_solve();  // JointState's solve fields are this step's only
  const uint64_t nonfinite_before = w.nonfinite_recoveries;
  w.refresh_moving_boxes();
  auto stage = [&w](Stage s, auto&& run) {
    const auto t0 = std::chrono::steady_clock::now();
    StageReport r = run();
    r.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    r.stage = s;
    w.report.stages[size_t(s)] = r;
  };
  stage(Stage::Skinning, [&] { return w.pose_hands(frames, dt); });        // lines 1-2: eq. 1, particle positions
  stage(Stage::Contacts, [&] { return w.detect_contacts(dt); });           // line 3
  stage(Stage::Deformation, [&] { return w.deform_hands(); });             // particles pushed back to the surface
  stage(Stage::Grasp, [&] { return w.decide_grasps(dt); });                // lines 4-9, 11-13, 16: eq. 3
  stage(Stage::Attach, [&] { return w.follow_primary_hands(); });          // lines 10, 14
  stage(Stage::PoseFit, [&] { return w.fit_touched_bodies(dt); });         // line 17: eq. 2
  stage(Stage::Dynamics, [&] { return w.simulate(dt); });                  // line 18
  stage(Stage::Joints, [&] { return w.solve_joints(dt); });                // line 19: eq. 4
  stage(Stage::Slip, [&] { return w.retake_secondary_hands(); });          // line 20: eq. 5
  w.report.nonfinite_bodies = int(w.nonfinite_recoveries - nonfinite_before);
  if (w.report.nonfinite_bodies > 0) w.report.warnings |= warning_bit(StepWarning::NonFiniteRecovered);
  w.time += dt;
  w.step_events = w.events.size();
  return w.report;
}

void World::Impl::validate_dt(double dt) const {
  validate::time_step(dt);
  // The clock is a double: at t = 1000 s a step below 1.1e-13 s would not advance it (and the hand history
  // would then see time stand still).
  if (!(time + dt > time))
    validate::fail("dt", validate::fmt(dt) + " s is below the clock's resolution at t = " + validate::fmt(time) +
                             " s (time + dt == time)");
}

void World::Impl::validate_hand_frame(const HandFrame& frame, const HandSlot& h, const std::string& argument) const {
  validate_frame(frame, argument);
  if (frame.handedness != h.def.handedness) validate::fail(argument + ".handedness", "does not match the hand it drives");
}

World::Impl::SlotFrames World::Impl::frames_by_id(double dt, const std::vector<HandInput>& inputs) const {
  validate_dt(dt);
  SlotFrames frames(hands.size(), nullptr);
  for (size_t k = 0; k < inputs.size(); ++k) {
    const std::string argument = "hands[" + std::to_string(k) + "]";
    const HandId id = inputs[k].hand;
    hand(id, (argument + ".hand").c_str());  // null or not a live hand of this world: StaleId
    if (frames[id.index]) {
      size_t first = 0;
      while (inputs[first].hand != id) ++first;
      validate::fail(argument + ".hand", "index " + std::to_string(id.index) + ", generation " +
                                             std::to_string(id.generation) + " already has a frame, in hands[" +
                                             std::to_string(first) + "]");
    }
    validate_hand_frame(inputs[k].frame, hands[id.index], argument + ".frame");
    frames[id.index] = &inputs[k].frame;
  }
  return frames;
}

World::Impl::SlotFrames World::Impl::frames_by_position(double dt, const std::vector<HandFrame>& list) const {
  validate_dt(dt);
  size_t live = 0;
  for (const HandSlot& h : hands) live += h.alive;
  if (list.size() > live)
    validate::fail("hands", "got " + std::to_string(list.size()) + " frames but the world has " +
                                std::to_string(live) + " hands");
  SlotFrames frames(hands.size(), nullptr);
  size_t k = 0;
  for (uint32_t i = 0; i < hands.size() && k < list.size(); ++i) {
    if (!hands[i].alive) continue;
    validate_hand_frame(list[k], hands[i], "hands[" + std::to_string(k) + "]");
    frames[i] = &list[k++];
  }
  return frames;
}

// --- line 18: physics for everything else, in fixed substeps ---
StageReport World::Impl::simulate(double dt) {
  const double h = def.fixed_substep;
  accumulator += dt;
  // The small tolerance keeps dt = 4h from yielding 3 substeps through rounding.
  int n = int(std::floor(accumulator / h + 1e-9));
  if (n > def.max_substeps) {
    n = def.max_substeps;
    report.dropped_seconds = accumulator - n * h;
    report.warnings |= warning_bit(StepWarning::SubstepsDropped);
    accumulator = n * h;  // drop what cannot be caught up
  }
  const bool physics = n > 0 && physics_needed(dt);
  for (int i = 0; i < n; ++i) substep(h, i, n, physics);
  accumulator = std::max(0.0, accumulator - n * h);
  if (n > 0)
    for (uint32_t bi : held_bodies())
      if (bodies[bi].motion == BodyMotion::Kinematic && !bodies[bi].jointed()) bodies[bi].synced_pose = bodies[bi].pose;
  report.substeps = n;
  report.bullet = physics;
  if (n == 0) return stage_skipped(SkipReason::BelowSubstep);
  return stage_work(n);
}

void World::Impl::substep(double h, int i, int n, bool physics) {
  // Kinematic bodies glide from the pose Bullet last saw to their target over the frame's substeps, so
  // Bullet derives the right velocity for pushing free bodies. (Declared kinematic bodies only move through
  // set_body_pose, which syncs them; the held ones are the gliders.)
  const double s = double(i + 1) / n;
  for (uint32_t bi : held_bodies()) {
    Body& b = bodies[bi];
    if (b.motion != BodyMotion::Kinematic || b.jointed()) continue;
    if (!physics && i + 1 < n) continue;  // nothing sees the glide; only where it ends
    Pose p{b.synced_pose.position + s * (b.pose.position - b.synced_pose.position),
           b.synced_pose.orientation.slerp(s, b.pose.orientation)};
    backend->move_kinematic(b.backend, i + 1 == n ? b.pose : p);
  }
  drive_soft_children(h);
  if (physics) {
    backend->step(h);
    read_dynamic_bodies();
  } else {
    backend->idle(h);
    ++idle_substeps;
  }
  if (!joint_order.empty()) {
    integrate_joints(h);
    place_children();  // after the parents moved, so a child rides on a falling or carried parent
  }
}

}  // namespace handsim
