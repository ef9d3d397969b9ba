// One frame: Algorithm 1 of Kim & Park, read top-down in World::step, and nothing else. Each stage, its math and
// the glue that runs it over the world's hands and bodies, lives in the file named after it (skinning,
// contacts, deformation, grasp, pose_fit, dynamics, world_joints); the step's input check is step_input.cpp.
#include "world_impl.h"

#include <algorithm>
#include <chrono>

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
  HandParticles particles = w.particles();
  Grasps grasps = w.grasps();
  track_hands(particles, frames, w.time, w.report, dt);  // the frame's bones, palms and their histories
  // A stage's seconds run from the end of the one before (the first's from here): one clock read a stage, not two
  // (a read is ~20 ns, a held lid's step ~3.5 us); what lies between two stages is the glue that hands one's report
  // over and, before the slip, the end of the releases.
  auto mark = std::chrono::steady_clock::now();
  auto stage = [&w, &mark](Stage s, auto&& run) {
    StageReport r = run();
    const auto end = std::chrono::steady_clock::now();
    r.seconds = std::chrono::duration<double>(end - mark).count();
    mark = end;
    r.stage = s;
    w.report.stages[size_t(s)] = r;
  };
  // Lines 10, 14, before the contacts: a held body moves with its hand, and a grip is relative, so the hand of this
  // frame is judged against the body where this frame's hand carries it (docs/grasp.md "The hold path"). A body
  // grasped in this frame's grasp stage follows its hand there. Then the boxes of what the last step's joints and
  // this carry moved, for the hand-body broadphase.
  stage(Stage::Attach, [&] {
    const StageReport r = follow_primary_hands(w.def, w.held_bodies(), w.bodies, w.hands, w, w.stop_scratch);
    w.refresh_moving_boxes();
    return r;
  });
  stage(Stage::Skinning, [&] { return pose_hands(particles); });           // lines 1-2: eq. 1
  stage(Stage::Contacts, [&] { return detect_contacts(particles, w.body_version, dt); });  // line 3
  stage(Stage::Deformation, [&] { return deform_hands(particles); });      // particles pushed back to the surface
  stage(Stage::Grasp, [&] { return decide_grasps(grasps, w.grasp_scratch, dt); });  // lines 4-9, 11-13, 16: eq. 3
  stage(Stage::PoseFit, [&] {                                               // line 17: eq. 2
    return fit_touched_bodies(w, w.bodies, w.joints, w.hands, w.pairs, w.held_bodies(), w.released, *w.backend, w,
                              w.pose_fit_scratch, dt);
  });
  stage(Stage::Dynamics, [&] {                                              // line 18
    return simulate(w, w, w.bodies, w.joints, w.hands, *w.backend, w.held_bodies(), w.dynamic_bodies(), w, w.report, dt);
  });
  stage(Stage::Joints, [&] {                                                // line 19: eq. 4
    return solve_joints(w, w.joints, w.bodies, w.hands, *w.backend, w.letting_go, dt);
  });
  grasps.finish_releases();  // the children let go of this step were carried to the frame's end: free from here
  stage(Stage::Slip, [&] { return retake_secondary_hands(w.held_bodies(), w.bodies, w.hands); });  // line 20: eq. 5
  w.report.nonfinite_bodies = int(w.nonfinite_recoveries - nonfinite_before);
  if (w.report.nonfinite_bodies > 0) w.report.warnings |= warning_bit(StepWarning::NonFiniteRecovered);
  w.record_body_paths(w.time + dt);  // the let-go's measure of the bodies' motion (BodyState::path)
  w.time += dt;
  w.step_events = w.events.size();
  return w.report;
}

}  // namespace handsim
