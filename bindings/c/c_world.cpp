// C ABI: the world's lifetime and settings, the step, what a step reports (stages, events, hash), and save and
// restore.
#include "c_api.h"

#include <cstring>

namespace handsim::capi {

// A step gets at most one frame per live hand: reject a wild count before converting anything (the core checks
// too, but only after the frames were converted). `what` names the array's elements in the message.
static void check_hand_count(const World& world, int32_t hand_count, const char* what) {
  const size_t live = world.hands().size();
  if (size_t(hand_count) > live)
    validate::fail("hands", "got " + std::to_string(hand_count) + " " + what + " but the world has " +
                                std::to_string(live) + " hands");
}

}  // namespace handsim::capi

using namespace handsim;
using namespace handsim::capi;

extern "C" {

HANDSIM_API int HANDSIM_CALL handsim_world_settings_default(handsim_world_settings* out_settings) {
  return guarded([&] { deref(out_settings, "out_settings") = as_c<handsim_world_settings>(WorldDef{}); });
}

HANDSIM_API int HANDSIM_CALL handsim_grasp_settings_contacts(handsim_grasp_settings* out_settings) {
  return guarded([&] { deref(out_settings, "out_settings") = as_c<handsim_grasp_settings>(GraspSettings::contacts()); });
}

HANDSIM_API int HANDSIM_CALL handsim_grasp_settings_paper(handsim_grasp_settings* out_settings) {
  return guarded([&] { deref(out_settings, "out_settings") = as_c<handsim_grasp_settings>(GraspSettings::paper()); });
}

HANDSIM_API int HANDSIM_CALL handsim_world_create(const handsim_world_settings* settings, handsim_world** out_world) {
  return guarded([&] {
    handsim_world*& out = deref(out_world, "out_world");
    const WorldDef def = settings ? from_c<WorldDef>(*settings) : WorldDef{};
    try {
      validate_grasp_settings(def.grasp);  // it names the bare field ("grasp_time_s")
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
    deref(out_settings, "out_settings") = as_c<handsim_world_settings>(w.def());
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

HANDSIM_API int HANDSIM_CALL handsim_save_state(handsim_world* world, uint8_t* out_bytes, int32_t capacity,
                                                int32_t* count) {
  return guarded([&] {
    const std::vector<uint8_t> bytes = checked(world).world.save_state();
    if (output_buffer(out_bytes, capacity, count, bytes.size(), "out_bytes"))
      std::memcpy(out_bytes, bytes.data(), bytes.size());
  });
}

HANDSIM_API int HANDSIM_CALL handsim_restore_state(handsim_world* world, const uint8_t* bytes, int32_t size) {
  return guarded([&] {
    handsim_world& w = checked(world);
    input_array(bytes, size, "state", "size");
    w.world.restore_state(bytes, size_t(size));
  });
}

HANDSIM_API int HANDSIM_CALL handsim_step(handsim_world* world, double dt, const handsim_hand_frame* hands,
                                          int32_t hand_count) {
  return guarded([&] {
    handsim_world& w = checked(world);
    input_array(hands, hand_count, "hands", "hand_count");
    check_hand_count(w.world, hand_count, "frames");
    // Per calling thread, not per world: two threads stepping one world must not share the scratch.
    thread_local std::vector<HandFrame> frames;
    frames.resize(size_t(hand_count));
    for (int32_t k = 0; k < hand_count; ++k)
      capi::to_cpp(hands[k], "hands[" + std::to_string(k) + "]", frames[size_t(k)]);
    w.world.step(dt, frames);
  });
}

HANDSIM_API int HANDSIM_CALL handsim_step_hands(handsim_world* world, double dt, const handsim_hand_input* hands,
                                                int32_t hand_count) {
  return guarded([&] {
    handsim_world& w = checked(world);
    input_array(hands, hand_count, "hands", "hand_count");
    // Each live hand has at most one entry, so a longer array repeats or names dead hands.
    check_hand_count(w.world, hand_count, "entries");
    thread_local std::vector<HandInput> inputs;  // per calling thread, as in handsim_step
    inputs.resize(size_t(hand_count));
    for (int32_t k = 0; k < hand_count; ++k) {
      inputs[size_t(k)].hand = HandId::unpack(hands[k].hand);
      capi::to_cpp(hands[k].frame, "hands[" + std::to_string(k) + "].frame", inputs[size_t(k)].frame);
    }
    w.world.step(dt, inputs);
  });
}

static_assert(HANDSIM_STAGE_COUNT == kStageCount, "handsim_step_report.stages has one slot per Stage");

HANDSIM_API int HANDSIM_CALL handsim_last_step(const handsim_world* world, handsim_step_report* out_report) {
  return guarded([&] {
    handsim_step_report& out = deref(out_report, "out_report");
    const StepReport r = checked(world).world.last_step();
    for (size_t k = 0; k < kStageCount; ++k) {
      const StageReport& s = r.stages[k];
      out.stages[k] = {s.seconds, int32_t(s.stage), int32_t(s.skip), s.work, s.particles};
    }
    out.dropped_seconds = r.dropped_seconds;
    out.warnings = r.warnings;
    out.substeps = r.substeps;
    out.bullet = r.bullet;
    out.nonfinite_bodies = r.nonfinite_bodies;
  });
}

HANDSIM_API int HANDSIM_CALL handsim_stage_reports(const handsim_world* world, handsim_stage_report* out_reports,
                                                   int32_t capacity, int32_t* count) {
  return guarded([&] {
    const StepReport r = checked(world).world.last_step();
    if (!output_buffer(out_reports, capacity, count, r.stages.size(), "out_reports")) return;
    for (size_t i = 0; i < r.stages.size(); ++i)
      out_reports[i] = {r.stages[i].seconds, r.stages[i].ran(), 0, r.stages[i].name()};
  });
}

HANDSIM_API int HANDSIM_CALL handsim_stage_summary(const handsim_world* world, char* out_text, int32_t capacity,
                                                   int32_t* length) {
  return guarded([&] {
    const std::string text = checked(world).world.stage_summary();
    if (output_buffer(out_text, capacity, length, text.size() + 1, "out_text", "length"))
      std::memcpy(out_text, text.c_str(), text.size() + 1);
  });
}

HANDSIM_API int HANDSIM_CALL handsim_events(const handsim_world* world, handsim_event* out_events, int32_t capacity,
                                            int32_t* count) {
  return guarded([&] {
    const std::vector<Event>& events = checked(world).world.events();
    if (!output_buffer(out_events, capacity, count, events.size(), "out_events")) return;
    for (size_t i = 0; i < events.size(); ++i)
      out_events[i] = as_c<handsim_event>(events[i]);
  });
}

}  // extern "C"
