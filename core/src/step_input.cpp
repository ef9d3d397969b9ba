// What a step is given -- dt and one frame per hand -- checked before anything changes, so a step refused on bad
// input leaves the world intact; the result is the per-slot frame table the stages read.
#include "validate.h"
#include "world_impl.h"

#include <string>

namespace handsim {

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

namespace {

// validate_hand_frame's conditions without building argument names: a frame that fits (every frame of every step,
// normally) costs no allocation; one that does not goes to validate_hand_frame, which names what is wrong.
bool fits(const HandFrame& frame, const HandSlot& h) {
  return frame_is_valid(frame) && frame.handedness == h.def.handedness;
}

}  // namespace

const SlotFrames& World::Impl::frames_by_id(double dt, const std::vector<HandInput>& inputs) const {
  validate_dt(dt);
  SlotFrames& frames = frames_by_id_scratch;
  frames.assign(hands.size(), nullptr);
  for (size_t k = 0; k < inputs.size(); ++k) {
    // The entry's name is built only for a message: a good entry (every entry of every step, normally) costs
    // no allocation.
    auto argument = [k] { return "hands[" + std::to_string(k) + "]"; };
    const HandId id = inputs[k].hand;
    if (!live_slot(hands, id)) hand(id, (argument() + ".hand").c_str());  // null or not live here: StaleId
    if (frames[id.index]) {
      size_t first = 0;
      while (inputs[first].hand != id) ++first;
      validate::fail(argument() + ".hand", "index " + std::to_string(id.index) + ", generation " +
                                               std::to_string(id.generation) + " already has a frame, in hands[" +
                                               std::to_string(first) + "]");
    }
    const HandFrame& frame = inputs[k].frame;
    if (!fits(frame, hands[id.index])) validate_hand_frame(frame, hands[id.index], argument() + ".frame");
    frames[id.index] = &frame;
  }
  return frames;
}

SlotFrames World::Impl::frames_by_position(double dt, const std::vector<HandFrame>& list) const {
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
    if (!fits(list[k], hands[i])) validate_hand_frame(list[k], hands[i], "hands[" + std::to_string(k) + "]");
    frames[i] = &list[k++];
  }
  return frames;
}

}  // namespace handsim
