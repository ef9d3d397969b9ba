// Object-centred pose update (Kim & Park, Section II-B, eq. 2): the rigid motion that best carries an
// object's contact points onto the hand particles that penetrate it.
//
// The paper writes   argmin_{R,t} sum_i |p_i - p'_i(R,t)|   with an un-squared norm. We solve the
// weighted *least-squares* version   argmin_{R,t} sum_i w_i |p_i - (R q_i + t)|^2   instead: it has a
// closed-form solution (Kabsch/Umeyama without scaling), is smooth in the inputs, and with exact data both
// problems share the same minimiser. The un-squared sum would need an iterative solver every frame.
#pragma once

#include "handsim/types.h"

#include <vector>

namespace handsim {

// A rigid motion x' = R x + t, stored together with its rotation centre so it can be applied to points
// far from the origin without cancellation: x' = x + (R - I)(x - pivot) + shift.
// Invariant: t == pivot + shift - R * pivot.
struct RigidMotion {
  Mat3 R = Mat3::Identity();
  Vec3 t = Vec3::Zero();
  Vec3 pivot = Vec3::Zero();  // rotation centre (the weighted centroid of the contact points q)
  Vec3 shift = Vec3::Zero();  // how far the pivot moves
  // How many of the 6 rigid DOFs the contacts determine: 0 (nothing: no contacts or no weight),
  // 3 (translation only: contacts coincide), 5 (contacts on a line: twist about it is free), 6 (all).
  // Undetermined DOFs get the minimal-norm motion (no translation / no rotation beyond what is needed).
  int constrained_dofs = 0;

  static RigidMotion identity() { return {}; }
  // Rotation R about `pivot`, then translation of the pivot by `shift`.
  static RigidMotion about(const Vec3& pivot, const Mat3& R, const Vec3& shift);

  Vec3 displacement(const Vec3& x) const { return (R - Mat3::Identity()) * (x - pivot) + shift; }
  Vec3 apply(const Vec3& x) const { return x + displacement(x); }
};

// Velocity of a rigid body: `linear` is the velocity of a chosen reference point (the centre of mass
// unless stated otherwise), `angular` is the world-frame angular velocity.
struct BodyVelocity {
  Vec3 linear = Vec3::Zero();
  Vec3 angular = Vec3::Zero();
};

// Thresholds of the rank decision in fit_rigid_motion (see pose_fit.cpp for the reasoning).
struct PoseFitTolerances {
  // RMS spread (m) of the contact points, or of the particles, below which they count as one point.
  // 1 nm: far below any hand-particle spacing (mm), far above the rounding of coordinates up to 1e5 m.
  double min_spread = 1e-9;
  // (sigma2 + d*sigma3) / sigma1 of the cross-covariance below which the contacts count as collinear,
  // i.e. a perpendicular spread below ~1e-4 of the spread along the line (the ratio is quadratic in it).
  double line_ratio = 1e-8;
};

// Weighted closed-form fit of the rigid motion carrying `from` (object surface points q_i, world) onto `to`
// (penetrating particle positions p_i, world). `weights` (e.g. penetration depths) must be finite and >= 0;
// an empty `weights` means all 1. Throws handsim::Error on size mismatch or non-finite / negative input.
// Never returns NaN: degenerate inputs get the minimal-norm motion described at RigidMotion::constrained_dofs.
RigidMotion fit_rigid_motion(const std::vector<Vec3>& from, const std::vector<Vec3>& to,
                             const std::vector<double>& weights = {},
                             const PoseFitTolerances& tolerances = {});

// The pose after the motion: position moved by the motion, orientation pre-multiplied by R.
Pose apply_motion(const RigidMotion& motion, const Pose& pose);

// The rotation vector (axis * angle, angle in [0, pi]) of a rotation; accurate for tiny angles.
Vec3 rotation_vector(const Quat& q);
Vec3 rotation_vector(const Mat3& R);

// `pose` moved for `t` seconds at a constant velocity (linear of its origin, angular about it).
Pose advanced(const Pose& pose, const Vec3& linear, const Vec3& angular, double t);

// The constant velocity that performs `motion` in `dt` seconds: angular = rotation_vector(R) / dt,
// linear = displacement of `centre_of_mass` / dt. Used so an object keeps moving once the hand leaves it.
// Throws handsim::Error when dt is not finite and > 0.
BodyVelocity velocity_from_motion(const RigidMotion& motion, const Vec3& centre_of_mass, double dt);

// One contact of the contact skin (WorldDef::skin_depth) or of the physical push (PushModel::Physical): the pulp
// between a particle and a body presses it along -normal. `hand_velocity` (m/s) is the hand's velocity at `point`:
// its component along -normal is the body's speed there that keeps the overlap from growing, its component along
// the surface is what the pulp's friction drags the contact point towards. `max_impulse` (N s) is what the pulp's
// pressure passes to the body within the frame; `friction` the Coulomb coefficient bounding the impulse along
// the surface by friction times the contact's normal impulse (0: the pulp only presses).
struct SkinContact {
  Vec3 point = Vec3::Zero();
  Vec3 normal = Vec3::UnitY();  // outward surface normal, unit
  Vec3 hand_velocity = Vec3::Zero();
  double max_impulse = 0;
  double friction = 0;
};

// One overlapping contact on a hinge's or slider's child, as overlap_step (pose_fit.cpp) weighs it: `breakpoint`, the
// step of the coordinate that clears it (depth / lever); `moment` and `square`, its lever times its depth and its
// lever squared (the lever: how far the point moves along its push per unit of the coordinate), summed over it and
// the contacts after it once sorted.
struct CoordinatePush {
  double breakpoint = 0;
  double moment = 0;
  double square = 0;
};

// A rigid body's inverse mass properties about its centre of mass, world frame.
struct InverseInertia {
  Vec3 centre = Vec3::Zero();
  double inverse_mass = 0;
  Mat3 inverse_inertia = Mat3::Zero();
};

// The body's velocity after the skin's impulses: each contact pushes (never pulls) at its point until the body
// moves away there at the hand's speed into it, by at most its max_impulse, and drags the point along the surface
// towards the hand's velocity there by at most friction times what it pushed; the contacts share the work by
// projected Gauss-Seidel over `iterations` sweeps in their given order (deterministic). So a light body is
// carried along by the hand (not faster: no contact gets more than it needs), a heavy one by no more than the
// pulp's force, and every impulse acts at its contact point, so a body pressed onto its support gets an impulse
// its support can take (Bullet's contact solver then cancels it) instead of eq. 2's fitted rotation.
// The same solve with unbounded impulses, no friction, a zero start and hand_velocity = -normal * overlap gives
// the least rigid displacement (in the body's mass and inertia metric) that moves every contact out by its
// overlap: the physical push removes the overlap with it (fit_touched_bodies, pose_fit.cpp).
// `tolerance` > 0 (m/s) stops the sweeps early once none changes the body's speed at a contact by more.
BodyVelocity skin_press(const std::vector<SkinContact>& contacts, const InverseInertia& body, const BodyVelocity& start,
                        int iterations = 8, double tolerance = 0);

}  // namespace handsim
