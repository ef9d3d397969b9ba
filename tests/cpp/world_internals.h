// White-box access for the tests that reach into World::Impl (World befriends this struct): test_state.cpp
// perturbs the state piece by piece, test_hold.cpp switches the hold path off to compare against it.
#pragma once

#include "handsim/world.h"
#include "world_impl.h"

namespace handsim {
struct WorldInternals {
  using Impl = World::Impl;
  static Impl& of(World& w) { return *w.impl_; }
};
}  // namespace handsim
