// The binders each bind_*.cpp file provides to module.cpp.
#pragma once

#include <pybind11/pybind11.h>

namespace handsim {
void bind_errors(pybind11::module_& m);
void bind_named_errors(pybind11::module_& m);  // the C call wrapper handsim.argument_errors puts on every callable
void bind_hand(pybind11::module_& m);
void bind_glove(pybind11::module_& m);  // after bind_hand: takes and returns HandFrames
void bind_step_report(pybind11::module_& m);  // before bind_world: World.step returns a StepReport
void bind_world(pybind11::module_& m);
void bind_world_hands(pybind11::module_& m);  // after bind_world: adds the hand methods to World
void bind_joints(pybind11::module_& m);  // adds the joint methods to World and WorldDef
void bind_user_aim(pybind11::module_& m);  // after bind_joints: takes a JewelryBox
}  // namespace handsim
