// Argument checks shared by every entry point (C++, Python and C all reach the core through these).
// Each check throws handsim::Error naming the argument; none of them mutates anything, so a caller that
// validates everything before touching state leaves the world intact on bad input.
#pragma once

#include "handsim/types.h"

#include <cmath>
#include <string>

namespace handsim::validate {

// Quaternions within this distance of unit length are normalized silently; beyond it they are rejected,
// because a caller passing |q| = 0.9 has a bug that normalizing would hide.
constexpr double kQuatTolerance = 1e-3;
constexpr double kMaxTimeStep = 60.0;  // seconds; longest frame step() accepts
// Bodies farther out or faster than this are a caller's bug; Bullet's broadphase overflows long before
// 1e300 and returns NaN. 1e7 m leaves room for planet-scale scenes; 1e4 m/s is 30x the speed of sound.
constexpr double kMaxCoordinate = 1e7;
constexpr double kMaxSpeed = 1e4;
// Hinge limits (radians): 159,155 turns either way; one ulp there is 1.2e-10 rad.
constexpr double kMaxJointAngle = 1e6;

[[noreturn]] void fail(const std::string& argument, const std::string& message,
                       Status status = Status::InvalidArgument);

std::string fmt(double v);
std::string fmt(const Vec3& v);

void finite(double v, const std::string& argument);
void finite(const Vec3& v, const std::string& argument);
void positive(double v, const std::string& argument);      // finite and > 0
void non_negative(double v, const std::string& argument);  // finite and >= 0
void positive(const Vec3& v, const std::string& argument);  // every component finite and > 0
// Returns the normalized quaternion, or throws when it is non-finite or too far from unit length.
Quat unit_quat(const Quat& q, const std::string& argument);
Pose pose(const Pose& p, const std::string& argument);
Pose body_pose(const Pose& p, const std::string& argument);
void point(const Vec3& v, const std::string& argument);  // finite, every |component| <= kMaxCoordinate  // pose() with |position| <= kMaxCoordinate
void velocity(const Vec3& v, const std::string& argument);
void at_most(double v, double limit, const std::string& argument);  // finite and <= limit  // finite, |v| <= kMaxSpeed  // finite position + unit_quat
Vec3 unit_vector(const Vec3& v, const std::string& argument);  // finite, non-zero; returned normalized
void time_step(double dt, const std::string& argument = "dt");

}  // namespace handsim::validate
