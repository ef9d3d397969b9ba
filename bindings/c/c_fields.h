// The field map of every C struct that mirrors a core struct (see HANDSIM_C_FIELDS in c_api.h): one list per
// struct converts in both directions, so a field added to one side and not mapped here shows up as a default.
#pragma once

#include "c_api.h"

namespace handsim::capi {

// The mirrored defs map the rows of handsim/def_table.h by name: a row without its C field does not compile.
#define HANDSIM_C_FIELD_ROW(Def, field) f(c.field, d.field);
#define HANDSIM_C_FIELD_MAP(Def, CStruct, ROWS) \
  HANDSIM_C_FIELDS(CStruct, Def) { ROWS(HANDSIM_C_FIELD_ROW) }
HANDSIM_C_FIELD_MAP(GraspSettings, handsim_grasp_settings, HANDSIM_FIELDS_GRASP_SETTINGS)

HANDSIM_C_FIELD_MAP(WorldDef, handsim_world_settings, HANDSIM_FIELDS_WORLD_DEF)

// The scalars of a shape; hull points and mesh indices are arrays the body conversion reads (c_bodies.cpp).
HANDSIM_C_FIELDS(handsim_shape, ShapeDef) {
  f(c.type, d.type);
  f(c.half_extents, d.half_extents);
  f(c.radius, d.radius);
  f(c.half_height, d.half_height);
}

HANDSIM_C_FIELD_MAP(BodyDef, handsim_body_def, HANDSIM_FIELDS_BODY_DEF)

HANDSIM_C_FIELDS(handsim_grasp_info, GraspInfo) {
  f(c.grasped, d.grasped);
  f(c.primary, d.primary);
  f(c.secondary, d.secondary);
  f(c.primary_relative, d.primary_relative);
}

HANDSIM_C_FIELDS(handsim_hinge_def, HingeDef) {
  f(c.parent, d.parent);
  f(c.child, d.child);
  f(c.pivot_parent, d.pivot_parent);
  f(c.axis_parent, d.axis_parent);
  f(c.pivot_child, d.pivot_child);
  f(c.axis_child, d.axis_child);
  f(c.lower, d.lower);
  f(c.upper, d.upper);
  f(c.damping, d.damping);
  f(c.has_rest_orientation, c.rest_orientation, d.rest_orientation, Quat::Identity());
  f(c.solver, d.solver);
  f(c.model, d.model);
}

HANDSIM_C_FIELDS(handsim_slider_def, SliderDef) {
  f(c.parent, d.parent);
  f(c.child, d.child);
  f(c.anchor_parent, d.anchor_parent);
  f(c.anchor_child, d.anchor_child);
  f(c.axis, d.axis);
  f(c.lower, d.lower);
  f(c.upper, d.upper);
  f(c.damping, d.damping);
  f(c.rest_orientation, d.rest_orientation);
  f(c.solver, d.solver);
  f(c.model, d.model);
}

HANDSIM_C_FIELDS(handsim_ball_def, BallDef) {
  f(c.parent, d.parent);
  f(c.child, d.child);
  f(c.pivot_parent, d.pivot_parent);
  f(c.pivot_child, d.pivot_child);
  f(c.rest_orientation, d.rest_orientation);
  f(c.cone_axis, d.cone_axis);
  f(c.has_cone_limit, c.cone_half_angle, d.cone_half_angle, 0.0);
  f(c.damping, d.damping);
  f(c.solver, d.solver);
  f(c.model, d.model);
}

HANDSIM_C_FIELDS(handsim_fixed_def, FixedDef) {
  f(c.parent, d.parent);
  f(c.child, d.child);
  f(c.relative, d.relative);
  f(c.model, d.model);
}

HANDSIM_C_FIELDS(handsim_joint_state, JointState) {
  f(c.type, d.type);
  f(c.model, d.model);
  f(c.solver, d.solver);
  f(c.solved, d.solved);
  f(c.parent, d.parent);
  f(c.child, d.child);
  f(c.value, d.value);
  f(c.rate, d.rate);
  f(c.rotation, d.rotation);
  f(c.violation, d.violation);
  f(c.overshoot, d.overshoot);
  f(c.cost, d.cost);
  f(c.iterations, d.iterations);
  f(c.termination, d.termination);
  f(c.solve_seconds, d.solve_seconds);
}

HANDSIM_C_FIELD_MAP(HandDef, handsim_hand_def, HANDSIM_FIELDS_HAND_DEF)

HANDSIM_C_FIELDS(handsim_joint_pose, JointPose) {
  f(c.position, d.position);
  f(c.orientation, d.orientation);
  f(c.radius, d.radius);
  f(c.valid, d.valid);
}

HANDSIM_C_FIELDS(handsim_hand_pose_params, HandPoseParams) {
  f(c.curl_thumb, d.curl[0]);
  f(c.curl_index, d.curl[1]);
  f(c.curl_middle, d.curl[2]);
  f(c.curl_ring, d.curl[3]);
  f(c.curl_little, d.curl[4]);
  f(c.thumb_opposition, d.thumb_opposition);
  f(c.spread, d.spread);
  f(c.scale, d.scale);
}

HANDSIM_C_FIELDS(handsim_event, Event) {
  f(c.type, d.type);
  f(c.reason, d.reason);
  f(c.hand, d.hand);
  f(c.body, d.body);
}

HANDSIM_C_FIELD_MAP(JewelryBoxDef, handsim_jewelry_box_def, HANDSIM_FIELDS_JEWELRY_BOX_DEF)

HANDSIM_C_FIELDS(handsim_jewelry_box, JewelryBox) {
  f(c.table, d.table);
  f(c.base, d.base);
  f(c.lid, d.lid);
  f(c.hinge, d.hinge);
  f(c.def, d.def);
}

#undef HANDSIM_C_FIELD_MAP
#undef HANDSIM_C_FIELD_ROW

}  // namespace handsim::capi
