// The field map of every C struct that mirrors a core struct (see HANDSIM_C_FIELDS in c_api.h): one list per
// struct converts in both directions, so a field added to one side and not mapped here shows up as a default.
#pragma once

#include "c_api.h"

namespace handsim::capi {

HANDSIM_C_FIELDS(handsim_grasp_settings, GraspSettings) {
  f(c.cos_threshold, d.cos_threshold);
  f(c.release_distance, d.release_distance);
  f(c.tracking_grace_s, d.tracking_grace_s);
  f(c.grasp_time_s, d.grasp_time_s);
  f(c.release_time_s, d.release_time_s);
  f(c.closing_distance, d.closing_distance);
  f(c.closing_window_s, d.closing_window_s);
  f(c.opening_distance, d.opening_distance);
  f(c.velocity_window, d.velocity_window);
  f(c.across_parts, d.across_parts);
}

HANDSIM_C_FIELDS(handsim_world_settings, WorldDef) {
  f(c.gravity, d.gravity);
  f(c.fixed_substep, d.fixed_substep);
  f(c.max_substeps, d.max_substeps);
  f(c.ground, d.ground);
  f(c.ground_height, d.ground_height);
  f(c.ground_friction, d.ground_friction);
  f(c.solver_iterations, d.solver_iterations);
  f(c.joint_max_iterations, d.joint_max_iterations);
  fields(c.grasp, d.grasp, f);
  f(c.particle_contacts, d.particle_contacts);
}

// The scalars of a shape; hull points and mesh indices are arrays the body conversion reads (c_bodies.cpp).
HANDSIM_C_FIELDS(handsim_shape, ShapeDef) {
  f(c.type, d.type);
  f(c.half_extents, d.half_extents);
  f(c.radius, d.radius);
  f(c.half_height, d.half_height);
}

HANDSIM_C_FIELDS(handsim_body_def, BodyDef) {
  fields(c.shape, d.shape, f);
  f(c.mass, d.mass);
  f(c.pose, d.pose);
  f(c.linear_velocity, d.linear_velocity);
  f(c.angular_velocity, d.angular_velocity);
  f(c.friction, d.friction);
  f(c.restitution, d.restitution);
  f(c.kinematic, d.kinematic);
}

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

HANDSIM_C_FIELDS(handsim_hand_def, HandDef) {
  f(c.handedness, d.handedness);
  f(c.particle_count, d.particle_count);
  f(c.sampling, d.sampling);
  f(c.render_vertices, d.render_vertices);
  f(c.seed, d.seed);
  f(c.particle_radius, d.particle_radius);
}

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

HANDSIM_C_FIELDS(handsim_jewelry_box_def, JewelryBoxDef) {
  f(c.position, d.position);
  f(c.yaw, d.yaw);
  f(c.base_half_extents, d.base_half_extents);
  f(c.lid_half_thickness, d.lid_half_thickness);
  f(c.lid_overhang, d.lid_overhang);
  f(c.base_mass, d.base_mass);
  f(c.lid_mass, d.lid_mass);
  f(c.lower, d.lower);
  f(c.upper, d.upper);
  f(c.damping, d.damping);
  f(c.friction, d.friction);
  f(c.table, d.table);
  f(c.model, d.model);
  f(c.solver, d.solver);
}

HANDSIM_C_FIELDS(handsim_jewelry_box, JewelryBox) {
  f(c.table, d.table);
  f(c.base, d.base);
  f(c.lid, d.lid);
  f(c.hinge, d.hinge);
  fields(c.def, d.def, f);
}

}  // namespace handsim::capi
