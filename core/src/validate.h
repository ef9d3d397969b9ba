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
// Sizes (m): below 0.1 um a shape is far under the hand's particle spacing (mm) and its inertia per kg
// (~ size^2) under 1e-14 (a denormal radius gave an inertia of 0). The thinnest shapes in the tests: the
// 1 um rod of stiff.ContactsWithin1umOfTheHingeAxis* (0.5 um half extents), the 1:1000 jewelry box (7.5 um).
constexpr double kMinSize = 1e-7;
// Masses (kg) of dynamic bodies: 1 mg .. 1000 t. Outside, inverse masses and inertias leave the range the
// contact solver handles (a 1e308 kg lid gave NaN); nothing a hand moves weighs more than a car.
constexpr double kMinMass = 1e-6;
constexpr double kMaxMass = 1e6;
// Friction coefficients: rubber on rubber is ~1-2; 100 already never slides, beyond it is a typo.
constexpr double kMaxFriction = 100;
// Gravity (m/s^2): 100 g. At the bound a body reaches the speed cap in 10 s; 1e308 made every state inf.
constexpr double kMaxGravity = 1e3;

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
// pose()'s conditions without an argument name: a per-step caller checks with it and calls pose(), which builds
// the name for its message, only when it fails.
bool is_pose(const Pose& p);
Pose body_pose(const Pose& p, const std::string& argument);
void point(const Vec3& v, const std::string& argument);  // finite, every |component| <= kMaxCoordinate
// finite and lo <= v <= hi; the message gives the range and the unit ("m", "kg", "" for none).
void in_range(double v, double lo, double hi, const std::string& argument, const char* unit);
void size(double v, const std::string& argument);       // in [kMinSize, kMaxCoordinate] m
void size(const Vec3& v, const std::string& argument);  // every component a size
void mass(double v, const std::string& argument);       // 0 (static) or in [kMinMass, kMaxMass] kg
void friction(double v, const std::string& argument);   // in [0, kMaxFriction]  // pose() with |position| <= kMaxCoordinate
void velocity(const Vec3& v, const std::string& argument);
void at_most(double v, double limit, const std::string& argument);  // finite and <= limit  // finite, |v| <= kMaxSpeed  // finite position + unit_quat
Vec3 unit_vector(const Vec3& v, const std::string& argument);  // finite, non-zero; returned normalized
void time_step(double dt, const std::string& argument = "dt");

}  // namespace handsim::validate
