// Joint definitions: how a child body is constrained to its parent (or to the world).
// Frames: every pivot/anchor/axis is given in the local frame of the body it belongs to. A null parent id
// means the world, whose frame is the identity.
#pragma once

#include "handsim/types.h"

#include <limits>
#include <optional>
#include <string>

namespace handsim {

// The values and what they mean: handsim/enum_table.h.
HANDSIM_DECLARE_ENUM(JointSolver, HANDSIM_ENUM_JOINT_SOLVER);
HANDSIM_DECLARE_ENUM(JointModel, HANDSIM_ENUM_JOINT_MODEL);
HANDSIM_DECLARE_ENUM(JointTermination, HANDSIM_ENUM_JOINT_TERMINATION);

constexpr double kUnlimited = std::numeric_limits<double>::infinity();

// Revolute joint. At angle theta the child pose is
//   C(theta) = P * Trans(pivot_parent) * Rot(axis_parent, theta) * R0 * Trans(-pivot_child)
// where R0 is the child's orientation relative to the parent at theta = 0; R0 maps axis_child onto
// axis_parent. Limits are radians: -inf/+inf for none, else within +-1e6; any span, also wider than 2*pi
// (the angle is unwrapped continuously and counts turns, so the lid turns more than once between its stops).
struct HingeDef {
  BodyId parent;  // null id: the world
  BodyId child;
  Vec3 pivot_parent = Vec3::Zero();
  Vec3 axis_parent = Vec3::UnitX();
  Vec3 pivot_child = Vec3::Zero();
  Vec3 axis_child = Vec3::UnitX();
  double lower = -kUnlimited;
  double upper = kUnlimited;
  double damping = 0.0;  // N*m*s/rad, >= 0; used by the world's dynamics, not by the micro-simulator
  // R0. Absent: the shortest-arc rotation taking axis_child onto axis_parent. Present: it must map
  // axis_child onto axis_parent (within 1e-6 rad) and is normalized.
  std::optional<Quat> rest_orientation;
  JointSolver solver = JointSolver::Exact;
  JointModel model = JointModel::Hard;
};

// Prismatic joint. At displacement s (metres) the child pose is
//   C(s) = P * Trans(anchor_parent + s * axis) * R0 * Trans(-anchor_child)
// i.e. the child keeps the orientation R0 relative to the parent and its anchor slides along `axis`.
struct SliderDef {
  BodyId parent;
  BodyId child;
  Vec3 anchor_parent = Vec3::Zero();
  Vec3 anchor_child = Vec3::Zero();
  Vec3 axis = Vec3::UnitX();  // parent frame
  double lower = -kUnlimited;
  double upper = kUnlimited;
  double damping = 0.0;  // N*s/m, >= 0
  Quat rest_orientation = Quat::Identity();  // R0
  JointSolver solver = JointSolver::Exact;
  JointModel model = JointModel::Hard;
};

// Spherical joint. With relative rotation R (identity at rest) the child pose is
//   C(R) = P * Trans(pivot_parent) * R * R0 * Trans(-pivot_child).
// Optional cone limit: the angle between cone_axis and R * cone_axis (the swing) may not exceed
// cone_half_angle, in [0, pi]. Twist about the cone axis is free.
struct BallDef {
  BodyId parent;
  BodyId child;
  Vec3 pivot_parent = Vec3::Zero();
  Vec3 pivot_child = Vec3::Zero();
  Quat rest_orientation = Quat::Identity();  // R0
  Vec3 cone_axis = Vec3::UnitY();            // parent frame; used only with a cone limit
  std::optional<double> cone_half_angle;     // radians; absent: no limit
  double damping = 0.0;                      // N*m*s/rad, >= 0
  JointSolver solver = JointSolver::Exact;   // only Exact is implemented for the ball joint
  JointModel model = JointModel::Hard;
};

// Weld: the child pose is P * relative.
struct FixedDef {
  BodyId parent;
  BodyId child;
  Pose relative;  // child pose in the parent frame
  JointModel model = JointModel::Hard;
};

// Throw handsim::Error(InvalidArgument) naming the field, e.g. "hinge.lower", on: non-finite or zero
// axis, non-finite pivot, NaN or out-of-range limit, lower > upper, child == parent, null child,
// negative or NaN damping, non-unit quaternion, unknown enum. Whether the ids are alive is the world's job.
void validate_joint(const HingeDef& def, const std::string& argument);
void validate_joint(const SliderDef& def, const std::string& argument);
void validate_joint(const BallDef& def, const std::string& argument);
void validate_joint(const FixedDef& def, const std::string& argument);

// A hinge through the world point `pivot_world` along `axis_world`, with the bodies' current poses as
// theta = 0 (the usual way to author one in an editor). Limits and solver are left at their defaults.
HingeDef hinge_from_world(BodyId parent, const Pose& parent_pose, BodyId child, const Pose& child_pose,
                          const Vec3& pivot_world, const Vec3& axis_world);

}  // namespace handsim
