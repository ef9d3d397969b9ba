// Where a simulated user (python/handsim/users.py) puts its right palm on the jewelry box's lid, every frame
// and more than once a frame: the closed-loop user aims at the lid where it sees it now. It is the hot part of
// the user's state machine after the glove (glove.h), so it lives here rather than in Python
// (docs/performance.md, "Sweeps"); the state machine that decides where to aim stays in Python.
#pragma once

#include "handsim/scenes.h"

namespace handsim {

// The palm of a right hand pinching the closed lid's lip (JewelryBox::lid_pinch_palm at angle 0), moved by
// `palm_shift` in its own frame (the user aims its virtual thumb, not its palm: the shift that puts a smaller
// or larger hand's thumb where an adult's goes; 0 for none) and by `box_shift` in the base's frame (the user's
// aim error, and how far it backs off past the lip or rises above it), then swung about the hinge by `angle`
// (rad) as if the lid were open by that much.
// Throws Error naming "angle", "palm_shift" or "box_shift" (or the stale base of a removed box).
Pose lid_grip_palm(const World& world, const JewelryBox& box, double angle, const Vec3& palm_shift,
                   const Vec3& box_shift);

}  // namespace handsim
