// C ABI: joints (hinge, slider, ball, fixed), their state and coordinate.
#include "c_api.h"

namespace handsim::capi {

static HingeDef to_cpp(const handsim_hinge_def& c) {
  HingeDef d;
  d.parent = body_id(c.parent);
  d.child = body_id(c.child);
  d.pivot_parent = capi::to_cpp(c.pivot_parent);
  d.axis_parent = capi::to_cpp(c.axis_parent);
  d.pivot_child = capi::to_cpp(c.pivot_child);
  d.axis_child = capi::to_cpp(c.axis_child);
  d.lower = c.lower;
  d.upper = c.upper;
  d.damping = c.damping;
  if (c.has_rest_orientation) d.rest_orientation = capi::to_cpp(c.rest_orientation);
  d.solver = JointSolver(c.solver);
  d.model = JointModel(c.model);
  return d;
}

static handsim_hinge_def to_c(const HingeDef& d) {
  handsim_hinge_def c{};
  c.parent = d.parent.packed();
  c.child = d.child.packed();
  c.pivot_parent = capi::to_c(d.pivot_parent);
  c.axis_parent = capi::to_c(d.axis_parent);
  c.pivot_child = capi::to_c(d.pivot_child);
  c.axis_child = capi::to_c(d.axis_child);
  c.lower = d.lower;
  c.upper = d.upper;
  c.damping = d.damping;
  c.rest_orientation = capi::to_c(d.rest_orientation.value_or(Quat::Identity()));
  c.has_rest_orientation = d.rest_orientation.has_value();
  c.solver = int32_t(d.solver);
  c.model = int32_t(d.model);
  return c;
}

static SliderDef to_cpp(const handsim_slider_def& c) {
  SliderDef d;
  d.parent = body_id(c.parent);
  d.child = body_id(c.child);
  d.anchor_parent = capi::to_cpp(c.anchor_parent);
  d.anchor_child = capi::to_cpp(c.anchor_child);
  d.axis = capi::to_cpp(c.axis);
  d.lower = c.lower;
  d.upper = c.upper;
  d.damping = c.damping;
  d.rest_orientation = capi::to_cpp(c.rest_orientation);
  d.solver = JointSolver(c.solver);
  d.model = JointModel(c.model);
  return d;
}

static handsim_slider_def to_c(const SliderDef& d) {
  handsim_slider_def c{};
  c.parent = d.parent.packed();
  c.child = d.child.packed();
  c.anchor_parent = capi::to_c(d.anchor_parent);
  c.anchor_child = capi::to_c(d.anchor_child);
  c.axis = capi::to_c(d.axis);
  c.lower = d.lower;
  c.upper = d.upper;
  c.damping = d.damping;
  c.rest_orientation = capi::to_c(d.rest_orientation);
  c.solver = int32_t(d.solver);
  c.model = int32_t(d.model);
  return c;
}

static BallDef to_cpp(const handsim_ball_def& c) {
  BallDef d;
  d.parent = body_id(c.parent);
  d.child = body_id(c.child);
  d.pivot_parent = capi::to_cpp(c.pivot_parent);
  d.pivot_child = capi::to_cpp(c.pivot_child);
  d.rest_orientation = capi::to_cpp(c.rest_orientation);
  d.cone_axis = capi::to_cpp(c.cone_axis);
  if (c.has_cone_limit) d.cone_half_angle = c.cone_half_angle;
  d.damping = c.damping;
  d.solver = JointSolver(c.solver);
  d.model = JointModel(c.model);
  return d;
}

static handsim_ball_def to_c(const BallDef& d) {
  handsim_ball_def c{};
  c.parent = d.parent.packed();
  c.child = d.child.packed();
  c.pivot_parent = capi::to_c(d.pivot_parent);
  c.pivot_child = capi::to_c(d.pivot_child);
  c.rest_orientation = capi::to_c(d.rest_orientation);
  c.cone_axis = capi::to_c(d.cone_axis);
  c.cone_half_angle = d.cone_half_angle.value_or(0.0);
  c.has_cone_limit = d.cone_half_angle.has_value();
  c.damping = d.damping;
  c.solver = int32_t(d.solver);
  c.model = int32_t(d.model);
  return c;
}

static FixedDef to_cpp(const handsim_fixed_def& c) {
  FixedDef d;
  d.parent = body_id(c.parent);
  d.child = body_id(c.child);
  d.relative = capi::to_cpp(c.relative);
  d.model = JointModel(c.model);
  return d;
}

static handsim_fixed_def to_c(const FixedDef& d) {
  handsim_fixed_def c{};
  c.parent = d.parent.packed();
  c.child = d.child.packed();
  c.relative = capi::to_c(d.relative);
  c.model = int32_t(d.model);
  return c;
}

static handsim_joint_state to_c(const JointState& s) {
  handsim_joint_state c{};
  c.type = int32_t(s.type);
  c.model = int32_t(s.model);
  c.solver = int32_t(s.solver);
  c.solved = s.solved;
  c.parent = s.parent.packed();
  c.child = s.child.packed();
  c.value = s.value;
  c.rate = s.rate;
  c.rotation = capi::to_c(s.rotation);
  c.violation = s.violation;
  c.overshoot = s.overshoot;
  c.cost = s.cost;
  c.iterations = s.iterations;
  c.termination = int32_t(s.termination);
  c.solve_seconds = s.solve_seconds;
  return c;
}

// The body of every handsim_add_<joint>: convert, add, hand out the id.
template <class CDef>
static int add_joint(handsim_world* world, const CDef* def, const char* def_name, handsim_joint_id* out_joint) {
  return guarded([&] {
    World& w = checked(world).world;
    const auto d = capi::to_cpp(deref(def, def_name));
    handsim_joint_id& out = deref(out_joint, "out_joint");
    out = w.add_joint(d).packed();
  });
}

// The body of every handsim_<joint>_def_default.
template <class CppDef, class CDef>
static int joint_default(CDef* out_def) {
  return guarded([&] { deref(out_def, "out_def") = capi::to_c(CppDef{}); });
}

}  // namespace handsim::capi

using namespace handsim;
using namespace handsim::capi;

extern "C" {

HANDSIM_API int HANDSIM_CALL handsim_hinge_def_default(handsim_hinge_def* out_def) {
  return joint_default<HingeDef>(out_def);
}
HANDSIM_API int HANDSIM_CALL handsim_slider_def_default(handsim_slider_def* out_def) {
  return joint_default<SliderDef>(out_def);
}
HANDSIM_API int HANDSIM_CALL handsim_ball_def_default(handsim_ball_def* out_def) {
  return joint_default<BallDef>(out_def);
}
HANDSIM_API int HANDSIM_CALL handsim_fixed_def_default(handsim_fixed_def* out_def) {
  return joint_default<FixedDef>(out_def);
}

HANDSIM_API int HANDSIM_CALL handsim_add_hinge(handsim_world* world, const handsim_hinge_def* hinge,
                                               handsim_joint_id* out_joint) {
  return add_joint(world, hinge, "hinge", out_joint);
}
HANDSIM_API int HANDSIM_CALL handsim_add_slider(handsim_world* world, const handsim_slider_def* slider,
                                                handsim_joint_id* out_joint) {
  return add_joint(world, slider, "slider", out_joint);
}
HANDSIM_API int HANDSIM_CALL handsim_add_ball(handsim_world* world, const handsim_ball_def* ball,
                                              handsim_joint_id* out_joint) {
  return add_joint(world, ball, "ball", out_joint);
}
HANDSIM_API int HANDSIM_CALL handsim_add_fixed(handsim_world* world, const handsim_fixed_def* fixed,
                                               handsim_joint_id* out_joint) {
  return add_joint(world, fixed, "fixed", out_joint);
}

HANDSIM_API int HANDSIM_CALL handsim_remove_joint(handsim_world* world, handsim_joint_id joint) {
  return guarded([&] { checked(world).world.remove_joint(joint_id(joint)); });
}

HANDSIM_API int HANDSIM_CALL handsim_contains_joint(const handsim_world* world, handsim_joint_id joint,
                                                    int32_t* out_alive) {
  return guarded([&] {
    const World& w = checked(world).world;
    deref(out_alive, "out_alive") = w.contains(joint_id(joint));
  });
}

HANDSIM_API int HANDSIM_CALL handsim_joints(const handsim_world* world, handsim_joint_id* out_joints,
                                            int32_t capacity, int32_t* count) {
  return guarded([&] {
    copy_ids(checked(world).world.joints(), out_joints, capacity, count, "out_joints");
  });
}

HANDSIM_API int HANDSIM_CALL handsim_get_joint_state(const handsim_world* world, handsim_joint_id joint,
                                                 handsim_joint_state* out_state) {
  return guarded([&] {
    const World& w = checked(world).world;
    handsim_joint_state& out = deref(out_state, "out_state");
    out = capi::to_c(w.joint_state(joint_id(joint)));
  });
}

HANDSIM_API int HANDSIM_CALL handsim_set_joint_value(handsim_world* world, handsim_joint_id joint, double value) {
  return guarded([&] { checked(world).world.set_joint_value(joint_id(joint), value); });
}

}  // extern "C"
