// C ABI: the world's lifetime and settings, the step, and what a step reports (stages, events, hash).
#include "c_api.h"

namespace handsim::capi {

static WorldDef to_cpp(const handsim_world_settings& s) {
  WorldDef d;
  d.gravity = to_cpp(s.gravity);
  d.fixed_substep = s.fixed_substep;
  d.max_substeps = s.max_substeps;
  d.ground = s.ground != 0;
  d.ground_height = s.ground_height;
  d.ground_friction = s.ground_friction;
  d.solver_iterations = s.solver_iterations;
  d.joint_max_iterations = s.joint_max_iterations;
  d.grasp.cos_threshold = s.grasp.cos_threshold;
  d.grasp.release_distance = s.grasp.release_distance;
  d.grasp.tracking_grace_s = s.grasp.tracking_grace_s;
  d.grasp.frames_to_grasp = s.grasp.frames_to_grasp;
  d.grasp.frames_to_release = s.grasp.frames_to_release;
  d.grasp.velocity_window = s.grasp.velocity_window;
  d.particle_contacts = WorldDef::ParticleContacts(s.particle_contacts);
  return d;
}

static handsim_world_settings to_c(const WorldDef& d) {
  handsim_world_settings s{};
  s.gravity = capi::to_c(d.gravity);
  s.fixed_substep = d.fixed_substep;
  s.max_substeps = d.max_substeps;
  s.ground = d.ground;
  s.ground_height = d.ground_height;
  s.ground_friction = d.ground_friction;
  s.solver_iterations = d.solver_iterations;
  s.joint_max_iterations = d.joint_max_iterations;
  s.grasp.cos_threshold = d.grasp.cos_threshold;
  s.grasp.release_distance = d.grasp.release_distance;
  s.grasp.tracking_grace_s = d.grasp.tracking_grace_s;
  s.grasp.frames_to_grasp = d.grasp.frames_to_grasp;
  s.grasp.frames_to_release = d.grasp.frames_to_release;
  s.grasp.velocity_window = d.grasp.velocity_window;
  s.particle_contacts = int32_t(d.particle_contacts);
  return s;
}

static size_t live_hands(const World& world) { return world.hands().size(); }

}  // namespace handsim::capi

using namespace handsim;
using namespace handsim::capi;

extern "C" {

HANDSIM_API int HANDSIM_CALL handsim_world_settings_default(handsim_world_settings* out_settings) {
  return guarded([&] { deref(out_settings, "out_settings") = capi::to_c(WorldDef{}); });
}

HANDSIM_API int HANDSIM_CALL handsim_world_create(const handsim_world_settings* settings, handsim_world** out_world) {
  return guarded([&] {
    handsim_world*& out = deref(out_world, "out_world");
    const WorldDef def = settings ? capi::to_cpp(*settings) : WorldDef{};
    try {
      validate_grasp_settings(def.grasp);  // it names the bare field ("frames_to_grasp")
    } catch (const Error& e) {
      rethrow_renamed(e, "", "settings.grasp.");
    }
    try {
      out = new handsim_world(def);
    } catch (const Error& e) {
      rethrow_renamed(e, "world", "settings");
    }
  });
}

HANDSIM_API int HANDSIM_CALL handsim_world_destroy(handsim_world* world) {
  return guarded([&] {
    if (!world) return;
    checked(world).magic = 0;
    delete world;
  });
}

HANDSIM_API int HANDSIM_CALL handsim_world_reset(handsim_world* world) {
  return guarded([&] { checked(world).world.reset(); });
}

HANDSIM_API int HANDSIM_CALL handsim_get_world_settings(const handsim_world* world, handsim_world_settings* out_settings) {
  return guarded([&] {
    const World& w = checked(world).world;
    deref(out_settings, "out_settings") = capi::to_c(w.def());
  });
}

HANDSIM_API int HANDSIM_CALL handsim_world_time(const handsim_world* world, double* out_time) {
  return guarded([&] {
    const World& w = checked(world).world;
    deref(out_time, "out_time") = w.time();
  });
}

HANDSIM_API int HANDSIM_CALL handsim_state_hash(const handsim_world* world, uint64_t* out_hash) {
  return guarded([&] {
    const World& w = checked(world).world;
    deref(out_hash, "out_hash") = w.state_hash();
  });
}

HANDSIM_API int HANDSIM_CALL handsim_step(handsim_world* world, double dt, const handsim_hand_frame* hands,
                                          int32_t hand_count) {
  return guarded([&] {
    handsim_world& w = checked(world);
    input_array(hands, hand_count, "hands", "hand_count");
    // The core checks this too, but only after the frames were converted: reject a wild count first.
    const size_t live = live_hands(w.world);
    if (size_t(hand_count) > live)
      validate::fail("hands", "got " + std::to_string(hand_count) + " frames but the world has " +
                                  std::to_string(live) + " hands");
    w.frames.resize(size_t(hand_count));
    for (int32_t k = 0; k < hand_count; ++k)
      capi::to_cpp(hands[k], "hands[" + std::to_string(k) + "]", w.frames[size_t(k)]);
    w.world.step(dt, w.frames);
  });
}

HANDSIM_API int HANDSIM_CALL handsim_stage_reports(const handsim_world* world, handsim_stage_report* out_reports,
                                                   int32_t capacity, int32_t* count) {
  return guarded([&] {
    const std::vector<StageReport>& reports = checked(world).world.stage_reports();
    if (!output_buffer(out_reports, capacity, count, reports.size(), "out_reports")) return;
    for (size_t i = 0; i < reports.size(); ++i)
      out_reports[i] = {reports[i].seconds, reports[i].ran, 0, reports[i].name};
  });
}

HANDSIM_API int HANDSIM_CALL handsim_stage_summary(const handsim_world* world, char* out_text, int32_t capacity,
                                                   int32_t* length) {
  return guarded([&] {
    const std::string text = checked(world).world.stage_summary();
    if (output_buffer(out_text, capacity, length, text.size() + 1, "out_text"))
      std::memcpy(out_text, text.c_str(), text.size() + 1);
  });
}

HANDSIM_API int HANDSIM_CALL handsim_events(const handsim_world* world, handsim_event* out_events, int32_t capacity,
                                            int32_t* count) {
  return guarded([&] {
    const std::vector<Event>& events = checked(world).world.events();
    if (!output_buffer(out_events, capacity, count, events.size(), "out_events")) return;
    for (size_t i = 0; i < events.size(); ++i)
      out_events[i] = {int32_t(events[i].type), int32_t(events[i].reason), events[i].hand.packed(),
                       events[i].body.packed()};
  });
}

}  // extern "C"
