#include "validate.h"

#include <cstdio>

namespace handsim::validate {

void fail(const std::string& argument, const std::string& message, Status status) {
  throw Error(status, argument, message);
}

std::string fmt(double v) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.6g", v);
  return buf;
}

std::string fmt(const Vec3& v) { return "(" + fmt(v.x()) + ", " + fmt(v.y()) + ", " + fmt(v.z()) + ")"; }

void finite(double v, const std::string& argument) {
  if (!std::isfinite(v)) fail(argument, "must be finite, got " + fmt(v));
}

void finite(const Vec3& v, const std::string& argument) {
  if (!v.allFinite()) fail(argument, "must be finite, got " + fmt(v));
}

void positive(double v, const std::string& argument) {
  if (!std::isfinite(v) || v <= 0) fail(argument, "must be finite and > 0, got " + fmt(v));
}

void non_negative(double v, const std::string& argument) {
  if (!std::isfinite(v) || v < 0) fail(argument, "must be finite and >= 0, got " + fmt(v));
}

void positive(const Vec3& v, const std::string& argument) {
  if (!v.allFinite() || (v.array() <= 0).any())
    fail(argument, "every component must be finite and > 0, got " + fmt(v));
}

Quat unit_quat(const Quat& q, const std::string& argument) {
  if (!q.coeffs().allFinite()) fail(argument, "quaternion must be finite");
  double n = q.norm();
  if (std::abs(n - 1.0) > kQuatTolerance)
    fail(argument, "quaternion (x,y,z,w) must have unit length (within 1e-3), got length " + fmt(n));
  return q.normalized();
}

Pose pose(const Pose& p, const std::string& argument) {
  finite(p.position, argument + ".position");
  return {p.position, unit_quat(p.orientation, argument + ".orientation")};
}

bool is_pose(const Pose& p) {
  return p.position.allFinite() && p.orientation.coeffs().allFinite() &&
         !(std::abs(p.orientation.norm() - 1.0) > kQuatTolerance);
}

void point(const Vec3& v, const std::string& argument) {
  finite(v, argument);
  if (!(v.cwiseAbs().maxCoeff() <= kMaxCoordinate))
    fail(argument, "must be within " + fmt(kMaxCoordinate) + " m of the origin, got " + fmt(v));
}

void in_range(double v, double lo, double hi, const std::string& argument, const char* unit) {
  if (!(v >= lo && v <= hi)) {
    const std::string u = *unit ? std::string(" ") + unit : std::string();
    fail(argument, "must be in [" + fmt(lo) + ", " + fmt(hi) + "]" + u + ", got " + fmt(v));
  }
}

void size(double v, const std::string& argument) { in_range(v, kMinSize, kMaxCoordinate, argument, "m"); }

void size(const Vec3& v, const std::string& argument) {
  if (!(v.array() >= kMinSize).all() || !(v.array() <= kMaxCoordinate).all())
    fail(argument, "every component must be in [" + fmt(kMinSize) + ", " + fmt(kMaxCoordinate) + "] m, got " + fmt(v));
}

void mass(double v, const std::string& argument) {
  if (v == 0) return;
  if (!(v >= kMinMass && v <= kMaxMass))
    fail(argument, "must be 0 (static) or in [" + fmt(kMinMass) + ", " + fmt(kMaxMass) + "] kg, got " + fmt(v));
}

void friction(double v, const std::string& argument) { in_range(v, 0, kMaxFriction, argument, ""); }

Pose body_pose(const Pose& p, const std::string& argument) {
  Pose out = pose(p, argument);
  point(p.position, argument + ".position");
  return out;
}

void at_most(double v, double limit, const std::string& argument) {
  if (!(v <= limit) || std::isnan(v)) fail(argument, "must be finite and <= " + fmt(limit) + ", got " + fmt(v));
}

void velocity(const Vec3& v, const std::string& argument) {
  finite(v, argument);
  if (!(v.norm() <= kMaxSpeed)) fail(argument, "must be at most " + fmt(kMaxSpeed) + " in magnitude, got " + fmt(v));
}

Vec3 unit_vector(const Vec3& v, const std::string& argument) {
  finite(v, argument);
  // stableNorm: the plain norm of (1e308, 0, 0) overflows to inf and the direction would become (0, 0, 0).
  double n = v.stableNorm();
  if (!(n > 1e-12)) fail(argument, "must be a non-zero direction, got " + fmt(v));
  return v / n;
}

void time_step(double dt, const std::string& argument) {
  if (!std::isfinite(dt) || dt <= 0) fail(argument, "must be finite and > 0, got " + fmt(dt));
  // A frame longer than a minute is a caller's bug (a timestamp passed as dt, say); it would also make the
  // world clock too coarse for the next frame's dt to advance it.
  if (dt > kMaxTimeStep) fail(argument, "must be <= " + fmt(kMaxTimeStep) + " s, got " + fmt(dt));
}

}  // namespace handsim::validate
