// The Python HandModel shared by bind_hand.cpp (which binds it) and bind_world_hands.cpp (World.hand_model).
#pragma once

#include "handsim/world.h"

#include <pybind11/pybind11.h>

#include <memory>

namespace handsim {

// Either owns a model (handsim.HandModel(definition, ...)) or names a hand of a World (World.hand_model(hand)).
// The world case looks the hand up on every access, so after remove_hand it raises StaleIdError instead of
// reading freed memory, and it keeps the Python World alive.
struct HandModelRef {
  std::shared_ptr<const HandModel> owned;
  pybind11::object world;
  HandId hand;

  const HandModel& get() const { return owned ? *owned : world.cast<const World&>().hand_model(hand); }
};

}  // namespace handsim
