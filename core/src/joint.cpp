#include "handsim/joint.h"

#include "validate.h"

#include <cmath>

namespace handsim {
namespace {

// R0 given by the user must carry axis_child onto axis_parent to this angle (radians).
constexpr double kRestAxisTolerance = 1e-6;

void check_bodies(BodyId parent, BodyId child, const std::string& arg) {
  if (child.is_null()) validate::fail(arg + ".child", "must be a body, got the null id (the world)");
  if (child == parent) validate::fail(arg + ".child", "must differ from the parent");
}

void check_model(JointModel m, const std::string& arg) {
  if (m != JointModel::Hard && m != JointModel::Soft)
    validate::fail(arg + ".model", "unknown joint model " + std::to_string(int(m)));
}

void check_solver(JointSolver s, const std::string& arg) {
  if (s != JointSolver::Exact && s != JointSolver::Lm && s != JointSolver::LmCeres)
    validate::fail(arg + ".solver", "unknown joint solver " + std::to_string(int(s)));
}

// Limits may be infinite (no limit on that side) but never NaN, and must leave a non-empty range. A finite
// limit is at most `bound` from 0 (1e6 rad, 1e7 m): there the coordinate still resolves 1.2e-10 rad resp.
// 1.9e-9 m (one ulp); far beyond, a stop would no longer be where it was asked for (1e308 was accepted).
void check_limits(double lower, double upper, const std::string& arg, double bound, const char* unit) {
  const std::string range = std::string(" (") + unit + "), got ";
  if (std::isnan(lower) || lower == kUnlimited || (std::isfinite(lower) && std::abs(lower) > bound))
    validate::fail(arg + ".lower", "must be -inf or finite within +-" + validate::fmt(bound) + range +
                                       validate::fmt(lower));
  if (std::isnan(upper) || upper == -kUnlimited || (std::isfinite(upper) && std::abs(upper) > bound))
    validate::fail(arg + ".upper", "must be +inf or finite within +-" + validate::fmt(bound) + range +
                                       validate::fmt(upper));
  if (lower > upper)
    validate::fail(arg + ".lower", "must be <= upper, got " + validate::fmt(lower) + " > " +
                                       validate::fmt(upper));
}

}  // namespace

void validate_joint(const HingeDef& d, const std::string& arg) {
  check_bodies(d.parent, d.child, arg);
  validate::point(d.pivot_parent, arg + ".pivot_parent");
  validate::point(d.pivot_child, arg + ".pivot_child");
  Vec3 ap = validate::unit_vector(d.axis_parent, arg + ".axis_parent");
  Vec3 ac = validate::unit_vector(d.axis_child, arg + ".axis_child");
  // Any span: the angle is unwrapped continuously (it counts turns), so a range wider than 2 pi is a joint
  // that turns more than once between its stops.
  check_limits(d.lower, d.upper, arg, validate::kMaxJointAngle, "rad");
  validate::non_negative(d.damping, arg + ".damping");
  if (d.rest_orientation) {
    Quat r0 = validate::unit_quat(*d.rest_orientation, arg + ".rest_orientation");
    Vec3 mapped = r0 * ac;
    double angle = std::atan2(mapped.cross(ap).norm(), mapped.dot(ap));
    if (angle > kRestAxisTolerance)
      validate::fail(arg + ".rest_orientation", "must map axis_child onto axis_parent, off by " +
                                                    validate::fmt(angle) + " rad");
  }
  check_solver(d.solver, arg);
  check_model(d.model, arg);
}

void validate_joint(const SliderDef& d, const std::string& arg) {
  check_bodies(d.parent, d.child, arg);
  validate::point(d.anchor_parent, arg + ".anchor_parent");
  validate::point(d.anchor_child, arg + ".anchor_child");
  validate::unit_vector(d.axis, arg + ".axis");
  check_limits(d.lower, d.upper, arg, validate::kMaxCoordinate, "m");
  validate::non_negative(d.damping, arg + ".damping");
  validate::unit_quat(d.rest_orientation, arg + ".rest_orientation");
  check_solver(d.solver, arg);
  check_model(d.model, arg);
}

void validate_joint(const BallDef& d, const std::string& arg) {
  check_bodies(d.parent, d.child, arg);
  validate::point(d.pivot_parent, arg + ".pivot_parent");
  validate::point(d.pivot_child, arg + ".pivot_child");
  validate::unit_quat(d.rest_orientation, arg + ".rest_orientation");
  if (d.cone_half_angle) {
    validate::unit_vector(d.cone_axis, arg + ".cone_axis");
    double a = *d.cone_half_angle;
    if (!(a >= 0 && a <= M_PI))
      validate::fail(arg + ".cone_half_angle", "must be in [0, pi], got " + validate::fmt(a));
  }
  validate::non_negative(d.damping, arg + ".damping");
  check_solver(d.solver, arg);
  if (d.solver != JointSolver::Exact)
    validate::fail(arg + ".solver", "the ball joint supports only JointSolver::Exact", Status::Unsupported);
  check_model(d.model, arg);
}

void validate_joint(const FixedDef& d, const std::string& arg) {
  check_bodies(d.parent, d.child, arg);
  validate::body_pose(d.relative, arg + ".relative");
  check_model(d.model, arg);
}

HingeDef hinge_from_world(BodyId parent, const Pose& parent_pose, BodyId child, const Pose& child_pose,
                          const Vec3& pivot_world, const Vec3& axis_world) {
  Pose p = validate::pose(parent_pose, "parent_pose");
  Pose c = validate::pose(child_pose, "child_pose");
  validate::point(pivot_world, "pivot_world");
  Vec3 axis = validate::unit_vector(axis_world, "axis_world");
  HingeDef d;
  d.parent = parent;
  d.child = child;
  d.pivot_parent = p.inverse_transform(pivot_world);
  d.pivot_child = c.inverse_transform(pivot_world);
  d.axis_parent = p.orientation.conjugate() * axis;
  d.axis_child = c.orientation.conjugate() * axis;
  d.rest_orientation = (p.orientation.conjugate() * c.orientation).normalized();
  return d;
}

}  // namespace handsim
