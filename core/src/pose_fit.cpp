#include "pose_fit.h"

#include "validate.h"
#include "world_impl.h"

#include <Eigen/SVD>

#include <algorithm>
#include <cmath>
#include <limits>

namespace handsim {
namespace {

// Checks element-wise and builds the argument name only on failure: this runs every frame on ~1000 points.
void check_points(const std::vector<Vec3>& points, const char* name) {
  for (size_t i = 0; i < points.size(); ++i)
    if (!points[i].allFinite()) validate::finite(points[i], std::string(name) + "[" + std::to_string(i) + "]");
}

void check_inputs(const std::vector<Vec3>& from, const std::vector<Vec3>& to,
                  const std::vector<double>& weights) {
  if (from.size() != to.size())
    validate::fail("to", "must have as many points as from (" + std::to_string(from.size()) + "), got " +
                             std::to_string(to.size()));
  if (!weights.empty() && weights.size() != from.size())
    validate::fail("weights", "must be empty or have one weight per point (" + std::to_string(from.size()) +
                                  "), got " + std::to_string(weights.size()));
  check_points(from, "from");
  check_points(to, "to");
  for (size_t i = 0; i < weights.size(); ++i)
    if (!(std::isfinite(weights[i]) && weights[i] >= 0))
      validate::non_negative(weights[i], "weights[" + std::to_string(i) + "]");
}

// Weights scaled so the largest is 1: sums of tiny (1e-300) or huge weights neither underflow nor overflow.
std::vector<double> normalized_weights(const std::vector<double>& weights, size_t n) {
  if (weights.empty()) return std::vector<double>(n, 1.0);
  double largest = *std::max_element(weights.begin(), weights.end());
  std::vector<double> w(weights);
  if (largest > 0)
    for (double& wi : w) wi /= largest;
  return w;
}

// A point set relative to its weighted centroid. The centroid is accumulated relative to an anchor (one of
// the points), so contacts 10 km from the origin keep their sub-micrometre offsets: summing raw coordinates
// of magnitude 1e4 would round every offset to ~1e-12 m before the SVD even starts.
struct Centred {
  Vec3 anchor = Vec3::Zero();
  Vec3 mean_offset = Vec3::Zero();  // centroid - anchor
  std::vector<Vec3> offsets;        // x_i - centroid
  double rms = 0;                   // weighted RMS distance from the centroid (m)
  Vec3 centroid() const { return anchor + mean_offset; }
};

Centred centre(const std::vector<Vec3>& x, const std::vector<double>& w, double wsum, size_t anchor) {
  Centred c;
  c.anchor = x[anchor];
  for (size_t i = 0; i < x.size(); ++i) c.mean_offset += w[i] * (x[i] - c.anchor);
  c.mean_offset /= wsum;
  c.offsets.resize(x.size());
  double sq = 0;
  for (size_t i = 0; i < x.size(); ++i) {
    c.offsets[i] = (x[i] - c.anchor) - c.mean_offset;
    sq += w[i] * c.offsets[i].squaredNorm();
  }
  c.rms = std::sqrt(sq / wsum);
  return c;
}

// The rotation part of the fit, from the weighted cross-covariance H = sum w q~ p~^T / W.
// Returns R and the number of DOFs it determines (3: none of the rotation, 5: all but the twist, 6: all).
std::pair<Mat3, int> fit_rotation(const Centred& q, const Centred& p, const std::vector<double>& w,
                                  double wsum, const PoseFitTolerances& tol) {
  // Coinciding contacts (or particles) say nothing about rotation: keep R = I (minimal norm).
  if (q.rms < tol.min_spread || p.rms < tol.min_spread) return {Mat3::Identity(), 3};
  Mat3 H = Mat3::Zero();
  for (size_t i = 0; i < w.size(); ++i) H += w[i] * q.offsets[i] * p.offsets[i].transpose();
  H /= wsum;
  Eigen::JacobiSVD<Mat3> svd(H, Eigen::ComputeFullU | Eigen::ComputeFullV);
  const Mat3& U = svd.matrixU();
  const Mat3& V = svd.matrixV();
  const Vec3& s = svd.singularValues();
  // sigma1 <= rms_q * rms_p (Cauchy-Schwarz), so this ratio is scale-free: ~0 means p is uncorrelated with q.
  if (s(0) <= tol.line_ratio * q.rms * p.rms) return {Mat3::Identity(), 3};
  // Reflection fix: a plain V U^T is a mirror when det(V U^T) = -1 (e.g. coplanar or mirrored data); the
  // best proper rotation flips the axis of the smallest singular value instead.
  double d = (V.determinant() * U.determinant()) < 0 ? -1.0 : 1.0;
  // The rotation is unique iff sigma2 + d*sigma3 > 0. When it is ~0 (collinear contacts, whatever their
  // count) every optimum maps u1 onto v1 and differs only by a twist about that line; the minimal-norm one
  // is the shortest arc from u1 to v1.
  if (s(1) + d * s(2) <= tol.line_ratio * s(0)) {
    Quat arc = Quat::FromTwoVectors(U.col(0), V.col(0));
    return {arc.normalized().toRotationMatrix(), 5};
  }
  Vec3 signs(1.0, 1.0, d);
  return {V * signs.asDiagonal() * U.transpose(), 6};
}

}  // namespace

RigidMotion RigidMotion::about(const Vec3& pivot, const Mat3& R, const Vec3& shift) {
  RigidMotion m;
  m.R = R;
  m.pivot = pivot;
  m.shift = shift;
  m.t = pivot + shift - R * pivot;
  return m;
}

RigidMotion fit_rigid_motion(const std::vector<Vec3>& from, const std::vector<Vec3>& to,
                             const std::vector<double>& weights, const PoseFitTolerances& tolerances) {
  check_inputs(from, to, weights);
  std::vector<double> w = normalized_weights(weights, from.size());
  double wsum = 0;
  size_t anchor = 0;
  for (size_t i = 0; i < w.size(); ++i) {
    if (wsum == 0 && w[i] > 0) anchor = i;
    wsum += w[i];
  }
  if (!(wsum > 0)) return RigidMotion::identity();  // no contacts, or none with weight: nothing moves
  Centred q = centre(from, w, wsum, anchor);
  Centred p = centre(to, w, wsum, anchor);
  auto [R, dofs] = fit_rotation(q, p, w, wsum, tolerances);
  // Anchors first: two nearby points 10 km out subtract exactly; adding the offsets' difference afterwards.
  Vec3 shift = (p.anchor - q.anchor) + (p.mean_offset - q.mean_offset);
  RigidMotion m = RigidMotion::about(q.centroid(), R, shift);
  m.constrained_dofs = dofs;
  return m;
}

Pose apply_motion(const RigidMotion& motion, const Pose& pose) {
  return {motion.apply(pose.position), (Quat(motion.R) * pose.orientation).normalized()};
}

Vec3 rotation_vector(const Quat& q_in) {
  Quat q = q_in.normalized();
  if (q.w() < 0) q.coeffs() = -q.coeffs();  // same rotation; picks the angle in [0, pi]
  double s = q.vec().norm();
  if (s == 0) return Vec3::Zero();
  // atan2 keeps full relative accuracy for tiny angles, where acos(w) would lose half the digits.
  double angle = 2.0 * std::atan2(s, q.w());
  return q.vec() * (angle / s);
}

Vec3 rotation_vector(const Mat3& R) { return rotation_vector(Quat(R)); }

// `pose` moved for `t` seconds at a constant velocity (linear of its origin, angular about it).
Pose advanced(const Pose& pose, const Vec3& linear, const Vec3& angular, double t) {
  const double turn = angular.norm() * t;
  const Quat spin = turn > 0 ? Quat(Eigen::AngleAxisd(turn, angular.normalized())) : Quat::Identity();
  return {pose.position + linear * t, (spin * pose.orientation).normalized()};
}

BodyVelocity velocity_from_motion(const RigidMotion& motion, const Vec3& centre_of_mass, double dt) {
  validate::time_step(dt);
  validate::finite(centre_of_mass, "centre_of_mass");
  BodyVelocity v;
  v.angular = rotation_vector(motion.R) / dt;
  v.linear = motion.displacement(centre_of_mass) / dt;
  return v;
}

BodyVelocity skin_press(const std::vector<SkinContact>& contacts, const InverseInertia& body, const BodyVelocity& start,
                        int iterations, double tolerance) {
  BodyVelocity v = start;
  std::vector<double> pushed(contacts.size(), 0.0);  // impulse each contact has passed so far (N s)
  std::vector<Vec3> dragged(contacts.size(), Vec3::Zero());  // and along the surface, by friction
  for (int sweep = 0; sweep < iterations; ++sweep) {
    double changed = 0;  // the largest change of the body's speed at a contact this sweep (m/s)
    for (size_t i = 0; i < contacts.size(); ++i) {
      const SkinContact& c = contacts[i];
      const Vec3 r = c.point - body.centre;
      const Vec3 in = -c.normal;  // the direction the pulp pushes the body
      const Vec3 arm = body.inverse_inertia * r.cross(in);
      const double response = body.inverse_mass + r.cross(in).dot(arm);  // speed along `in` per N s at the point
      if (!(response > 0)) continue;  // an immovable body
      const double speed = (v.linear + v.angular.cross(r)).dot(in);
      const double total = std::clamp(pushed[i] + (c.hand_velocity.dot(in) - speed) / response, 0.0, c.max_impulse);
      const double impulse = total - pushed[i];
      pushed[i] = total;
      v.linear += body.inverse_mass * impulse * in;
      v.angular += impulse * arm;
      changed = std::max(changed, std::abs(impulse) * response);
      if (!(c.friction > 0)) continue;
      // Friction: the impulse along the surface that brings the point's sliding to the hand's, its sum over the
      // sweeps kept within the cone |dragged| <= friction * pushed (Coulomb).
      const Vec3 slip = c.hand_velocity - (v.linear + v.angular.cross(r));
      const Vec3 along = slip - slip.dot(in) * in;
      const double sliding = along.norm();
      Vec3 total_drag = dragged[i];
      if (sliding > 0) {
        const Vec3 t = along / sliding;
        const Vec3 arm_t = body.inverse_inertia * r.cross(t);
        total_drag += sliding / (body.inverse_mass + r.cross(t).dot(arm_t)) * t;
      }
      const double cone = c.friction * pushed[i];
      if (total_drag.norm() > cone) total_drag *= cone / total_drag.norm();
      const Vec3 drag = total_drag - dragged[i];
      dragged[i] = total_drag;
      v.linear += body.inverse_mass * drag;
      v.angular += body.inverse_inertia * r.cross(drag);
      changed = std::max(changed, (body.inverse_mass * drag + (body.inverse_inertia * r.cross(drag)).cross(r)).norm());
    }
    if (changed <= tolerance) break;
  }
  return v;
}

// A contact as the pulp presses it (within WorldDef::skin_depth, or any contact of the physical push). It keeps
// the body from entering the hand further: the body must move away at the hand's own speed into it there, the
// palm's rigid motion at the point, or for a hand closing its grip (`closing`, PushModel::Wrap) the point's own
// motion on its bone: the finger flexors drive a closing finger at its own articulated speed, and where it meets a
// body it pushes the body at that speed. Measured by the palm's motion, a still palm whose fingers curl gives the
// body nothing and the tracked fingers curl on through it (docs/grasp.md "Wrap: a closing hand presses"). The pulp
// does not spring back: it is strongly damped (it recovers over a few hundred ms), so a body lying in it stays where
// the hand left it instead of being pushed out of a resting hand every frame. The pressure grows linearly with the
// compression up to skin_pressure at skin_depth and stays there beyond it (the bone takes the rest; without a skin,
// skin_depth = 0, the pulp is fully compressed at once), over the skin area the particle stands for (hexagonal
// spacing s: (sqrt(3)/2) s^2 each), for the frame's dt.
// `friction`: the pulp's Coulomb coefficient along the surface (0: it only presses).
namespace {

SkinContact skin_contact(const WorldDef& def, const ParticleContact& c, const HandSlot& hand, double dt, double friction,
                         bool closing = false) {
  const double spacing = hand.model->particle_spacing;
  const double area = std::sqrt(3.0) / 2 * spacing * spacing;
  const double compressed = def.skin_depth > 0 ? std::min(1.0, c.depth / def.skin_depth) : 1.0;
  SkinContact s;
  s.point = c.point;
  s.normal = c.normal;
  s.hand_velocity = closing ? particle_velocity(def, hand, c.particle, c.point) : hand.history.point_velocity(c.point);
  s.max_impulse = def.skin_pressure * compressed * area * dt;
  // A closing hand's finger that does not move into the body there did not press into it: the body came to it
  // (pushed by another finger) and its bone stops it, at any force, as the physical push's overlap removal does; the
  // overlap stays (no shove), only further entry is stopped.
  if (closing && !(s.hand_velocity.dot(-c.normal) > 0)) s.max_impulse = std::numeric_limits<double>::infinity();
  s.friction = friction;
  return s;
}

// The body's inverse mass and inertia in the world frame (unit_inertia: principal moments per kg, body frame).
InverseInertia inverse_inertia(const Body& b) {
  InverseInertia inv;
  inv.centre = b.pose.position;
  if (!(b.mass > 0)) return inv;
  inv.inverse_mass = 1 / b.mass;
  Vec3 moments;
  for (int k = 0; k < 3; ++k) moments[k] = b.unit_inertia[k] > 0 ? 1 / (b.mass * b.unit_inertia[k]) : 0.0;
  const Mat3 R = b.pose.orientation.toRotationMatrix();
  inv.inverse_inertia = R * moments.asDiagonal() * R.transpose();
  return inv;
}

// The Coulomb coefficient of the finger pulp along a body's surface (PushModel::Physical). Measured dry finger-pad
// friction against smooth materials (glass, metals, plastics) lies at about 0.5 to 1 and rises with sweat
// (reviewed by Derler & Gerhardt, Tribology Letters 45, 2012); 0.5, the dry end, because a hand's grazing
// contacts are as often the dry sides and backs of the fingers as moist pads.
constexpr double kPulpFriction = 0.5;
// A body resting on static geometry under a press (physical_push): the support's contacts bear loads with no bound,
// so the load passes between the hand's contacts and the support's over many sweeps, and a solve stopped early
// leaves the press's sideways parts (a palm's particles on a box's edges push down and out, in pairs that cancel
// only once solved) as a slide or a turn. So it sweeps until no contact changes the body's speed at it by more than
// 0.1 mm/s (2 micrometres of motion in a 60 Hz frame, far below a tracker's millimetre), at most 256 sweeps.
constexpr int kSupportSweeps = 256;
constexpr double kSupportSettled = 1e-4;

// PushModel::Wrap: whether `hand` is closing its grip, by the closing rule's own test (its grip span shrank by
// GraspSettings::closing_distance within closing_window_s; never with closing_distance 0). A closing hand's fingers
// are driven by the finger flexors and stop where they meet the body; where the tracked finger goes on into it, the
// real one pressed on its surface. So its overlap is pulp pressing, not bone shoving the body out of the way
// (docs/grasp.md "Wrap: a closing hand presses, it does not shove").
bool wraps(const WorldDef& def, const HandSlot& hand) {
  return def.push_model == PushModel::Wrap && def.grasp.closing_distance > 0 &&
         hand.grip.closed_by() >= def.grasp.closing_distance;
}

// The body's velocity as the let-go measures it (moved_into): the least-squares slope of its path (BodyState::path)
// over the window a particle's is measured over, ending when the particle's does, at this frame's end, where the
// body's own velocity carries it. Moving into a body is relative motion, so both sides are measured alike. Its
// one-step velocity would not do: held up to the release, that is the hand's last step, in which one tracker jump of
// the grip reads jump / dt (5 deg in one 60 Hz step: 310 deg/s, docs/grasp.md "Under Wrap", frame rates), while the
// fingers carried by the same jump read it over the window; the difference counted as the fingers moving into the
// body by an amount that depended on which frame held the jump. Nor would the path alone: its newest pose is the
// last frame's end, one frame behind the particles', so a jump it made in its last step counted against fingers that
// had made it too. Its own velocity where it has no path yet.
BodyVelocity let_go_velocity(const Body& b, double dt) {
  if (b.path.size() == 0) return {b.linear, b.angular};
  HandMotionHistory ahead = b.path;
  ahead.push(advanced(b.pose, b.linear, b.angular, dt), b.path.newest_time() + dt);
  return {ahead.linear_velocity(), ahead.angular_velocity()};  // of its origin, as b.linear and b.angular are
}

// How far contact `c`'s particle moved into `b` through its face this frame: the particle's own velocity (its bone's
// motion, palm and articulation together, as Wrap's press measures a closing finger's) less the body's at the point
// (`body`, let_go_velocity), along -normal, over dt; never negative. The overlap of a hand that let go of the body
// (HandBodyPair::let_go) is removed only this far: the rest is the grip's depth, which the hold left and the release
// did not push.
double moved_into(const WorldDef& def, const HandSlot& hand, const Body& b, const BodyVelocity& body,
                  const ParticleContact& c, double dt) {
  const Vec3 particle = particle_velocity(def, hand, c.particle, c.point);
  const Vec3 at = body.linear + body.angular.cross(c.point - b.pose.position);
  return std::max(0.0, (particle - at).dot(-c.normal) * dt);
}

// PushModel::Wrap: whether a closing hand's (`wraps`) contact `c` leaves a free body (no joint; resting on a support
// or floating) where it is: a contact of a digit (a phalanx of the thumb or a finger: rigid_part other than the palm).
// In reach to grasp the digits' closing is stopped at contact and the grip forms on the object without displacing it,
// whether or not a table holds the object; the tracked digit going on into the body is the recording of a hand that
// closed on nothing (the judge places its objects into recordings made without them), not a push. The palm is carried
// by the arm and presses as before (docs/grasp.md "A closing digit does not displace a free body").
bool forms_grip(const HandSlot& hand, const ParticleContact& c) { return rigid_part(*hand.model, c.particle) != kPalm; }

// A velocity the press leaves that is zero but for its rounding (m/s): 1e-9 m/s moves a body 1.7e-11 m in a 60 Hz
// frame, and the velocity solve of a lid lying still on still fingers leaves some 1e-19 m/s either way.
constexpr double kAtRest = 1e-9;

// A touched body gets the velocity eq. 2 or the skin gave it for this frame, from the pose `from` (b.pose, or where
// the physical push's displacement put it: moved_out). `from_below`: one of the pressing contacts pushes against
// gravity (its surface faces down).
void push_touched_body(const WorldDef& def, std::vector<Body>& bodies, std::vector<Joint>& joints, BulletBackend& backend,
                       Body& b, const Pose& from, const Vec3& linear, const Vec3& angular, double dt,
                       bool from_below = false) {
  if (b.jointed()) {
    Joint& j = joints[b.hard_joint];
    // The joint integrates gravity itself; a push against it carries the child's weight for the frame, and so does
    // a press from below that leaves the child at rest (a lid lying still on still fingers). Taken on the sign of
    // its velocity alone, that rest was decided by rounding: a lid let go of onto a still thumb was borne at 120 Hz
    // (+7.6e-20 m/s up) and at 30 Hz fell a frame's gravity into it (-7.4e-19), rocked and slipped off the lip
    // (docs/grasp.md "Under Wrap", frame rates).
    const double down = linear.dot(def.gravity);  // its speed along gravity times g
    b.supported = down < 0 || (from_below && std::abs(down) <= kAtRest * def.gravity.norm());
    // The push moves the child only along its joint: the frame's motion projected by the micro-simulator.
    project_push(def, bodies, j, advanced(from, linear, angular, dt), dt);
    return;
  }
  b.pose = from;
  b.linear = linear;
  b.angular = angular;
  backend.write(b.backend, b.pose, b.linear, b.angular);
}

// The friction angle's bound on a push that turns a hinge's child (or slides a slider's): a finger pressing along
// its normal while the child's surface point must slide under it to move along its path (at angle phi to the
// push) drives it with n cos(phi) and is held back by the pulp's friction, up to mu n sin(phi); past
// tan(phi) = 1 / mu the push jams (a wedge's self-locking) and the joint bears it. kPulpFriction 0.5: phi > 63.4
// deg, i.e. the push's share along the path below mu / sqrt(1 + mu^2) = 0.447.
const double kJammed = kPulpFriction / std::sqrt(1 + kPulpFriction * kPulpFriction);

// A hinge's or slider's child out of the bone's overlap (`overlap`): the step of its coordinate (docs/grasp.md "Why
// a push depends on the frame rate"). Each contact pushes its point of the child along -normal, and a step q of
// the coordinate moves that point along its path (coordinate_motion), by lever * q along the push. The step is
// where the contacts' pushes balance about the joint, each pushing as a spring while it overlaps:
// sum lever (depth - lever q)+ = 0, over the contacts that can drive the joint (not jammed: kJammed). Overlap on
// one side only is all cleared; fingers past both faces of a lid, which no step clears, leave it where the two
// sides' pushes balance, whatever the contacts' order. (The 6-DOF least displacement projected on the joint, a
// Gauss-Seidel solve of such an overlap, grew its impulses every sweep and stopped where the last contacts in its
// order pulled: the lid jumped +-2 deg frame to frame.) A push near the lid's radius jams: the hinge bears it, so
// it cannot throw the lid by depth / (its tiny lever).
double overlap_step(const std::vector<Body>& bodies, const Joint& j, const std::vector<SkinContact>& overlap,
                    std::vector<CoordinatePush>& levers) {
  levers.clear();
  double moment = 0;  // about the joint at q = 0 (every contact overlaps there), positive: the step goes up
  for (const SkinContact& c : overlap) {
    const Vec3 path = coordinate_motion(bodies, j, c.point);
    const double lever = -c.normal.dot(path);
    if (!(std::abs(lever) >= kJammed * path.norm()) || !(lever != 0)) continue;
    const double depth = -c.hand_velocity.dot(c.normal);  // the overlap contact's "speed" is the overlap
    levers.push_back({depth / lever, lever * depth, lever * lever});
    moment += lever * depth;
  }
  if (!(moment != 0)) return 0;
  const double sign = moment > 0 ? 1.0 : -1.0;  // the way the step goes
  // The contacts pushing against the step overlap more the further it goes: always active. Those pushing with it
  // are active until the step clears them (their breakpoints, measured the way the step goes).
  double resisting_moment = 0, resisting_square = 0;
  size_t pushing = 0;
  for (const CoordinatePush& l : levers) {
    if (l.breakpoint * sign > 0) {
      levers[pushing++] = {l.breakpoint * sign, l.moment, l.square};
    } else {
      resisting_moment += l.moment;
      resisting_square += l.square;
    }
  }
  levers.resize(pushing);
  // The balance: where sum lever (depth - lever q)+ (non-increasing in q) crosses zero. Between two breakpoints
  // the active contacts are those clearing later and every resisting one: q = their moments / their squares.
  std::sort(levers.begin(), levers.end(),
            [](const CoordinatePush& a, const CoordinatePush& b) { return a.breakpoint < b.breakpoint; });
  for (size_t k = levers.size() - 1; k-- > 0;) {  // sums over each contact and those clearing after it
    levers[k].moment += levers[k + 1].moment;
    levers[k].square += levers[k + 1].square;
  }
  for (const CoordinatePush& l : levers) {
    const double balanced = (l.moment * sign + resisting_moment * sign) / (l.square + resisting_square);
    if (balanced <= l.breakpoint) return sign * balanced;
  }
  return sign * levers.back().breakpoint;  // nothing resists: the last contact to clear sets the step
}

// PushModel::Physical's displacement out of the bone's overlap (scratch.overlap), with no velocity: the pose it
// puts `b` at. A free body (or a ball joint's child, then projected on its joint) moves by the least rigid
// displacement in its mass and inertia metric that moves every contact out by its overlap; a hinge's or slider's
// child steps its coordinate (overlap_step).
Pose moved_out(const WorldDef& def, std::vector<Body>& bodies, std::vector<Joint>& joints, PoseFitScratch& scratch,
               const Body& b, const InverseInertia& inverse, double dt) {
  if (b.jointed()) {
    Joint& j = joints[b.hard_joint];
    if (j.type == JointType::Hinge || j.type == JointType::Slider) {
      shift_coordinate(bodies, j, overlap_step(bodies, j, scratch.overlap, scratch.levers));
      return joint_child_pose(bodies, j);
    }
  }
  const BodyVelocity shift = skin_press(scratch.overlap, inverse, {});
  const Pose from = advanced(b.pose, shift.linear, shift.angular, 1.0);
  // The displacement is set at once, as a grasped child's pose is (no joint rate from it).
  if (b.jointed()) solve_grasped(def, bodies, joints[b.hard_joint], from, dt);
  return from;
}

// PushModel::Physical: the pulp's bounded impulses (`pressed`) set the velocity; the least displacement out of the
// bone's overlap (`overlap`) moves a free body without any (docs/grasp.md "Push models"). A body resting on static
// geometry (support_contacts) is held by its support instead (docs/grasp.md "A resting body's support bears the
// press"):
// - the support joins the velocity solve as contacts that push and never pull, with no bound and the surfaces'
//   friction, so what the hand presses into the support the support bears, as a table bears a palm pressing a plate
//   onto it; only what would lift, slide or tip the body moves it. The solve starts from the body's velocity plus
//   this frame's gravity, so the support also bears the weight: its friction holds the weight's share of the load,
//   and a press tips the body about an edge of its footprint only when its moment beats the weight's. The result
//   goes to Bullet as it is (Bullet's substeps add the gravity again and its contact with the support takes it
//   back; a body the press lifts off loses that frame's g dt twice).
// - no displacement: the bone's overlap is what the tracked hand, which nothing stops, passes into a body its
//   support and friction hold against the pulp's bounded force; pushed out kinematically it went into the support
//   and Bullet pushed it back into the hand every frame (the first touch's creep, a base shoved off its table).
// Jointed children rest on their joint, not on static geometry: they are pushed as free bodies are, in the world
// (the hands' velocities are the world's, and the child's own is its parent's rigid motion plus its joint's:
// place_children), from where the joint puts them on their parent as it is now. Only the motion relative to the
// parent is the joint's: the parent's rigid motion at the child comes off before the projection, which measures the
// child against the parent where it stands. (Projected whole, a parent's motion moved the joint: a base held by a
// jittering hand, 0.55 rad/s about the vertical, turned the lid it carried at 100 deg/s about its hinge,
// docs/grasp.md "Under Wrap".)
void physical_push(const WorldDef& def, std::vector<Body>& bodies, std::vector<Joint>& joints, BulletBackend& backend,
                   const BodyBoxes& boxes, PoseFitScratch& scratch, Body& b, double dt) {
  std::vector<SkinContact>& pressed = scratch.pressed;
  const std::vector<SkinContact>& support = scratch.support;  // support_contacts of `b`, as the caller found them
  const InverseInertia inverse = inverse_inertia(b);
  const bool displaced = support.empty() && !scratch.overlap.empty();
  const Pose from = displaced    ? moved_out(def, bodies, joints, scratch, b, inverse, dt)
                    : b.jointed() ? joint_child_pose(bodies, joints[b.hard_joint])
                                  : b.pose;
  const Vec3 weight = def.gravity * dt;
  pressed.insert(pressed.end(), support.begin(), support.end());
  BodyVelocity v = support.empty() ? skin_press(pressed, inverse, {b.linear, b.angular})
                                   : skin_press(pressed, inverse, {b.linear + weight, b.angular}, kSupportSweeps,
                                                kSupportSettled);
  if (b.jointed()) {
    const BodyVelocity carried = parent_motion(bodies, joints[b.hard_joint], from.position);
    v.linear -= carried.linear;
    v.angular -= carried.angular;
  }
  const bool from_below = std::any_of(pressed.begin(), pressed.end(),
                                      [&](const SkinContact& c) { return c.normal.dot(def.gravity) > 0; });
  push_touched_body(def, bodies, joints, backend, b, from, v.linear, v.angular, dt, from_below);
}

}  // namespace

// --- line 17: object-centred pose update of touched, ungrasped objects (eq. 2) ---
// The fitted motion is applied as a velocity over this frame rather than as a teleport: in free space both
// give the same pose, but with a velocity Bullet still resolves the table and other bodies, so a hand
// pressing a box down cannot push it through the table. The velocity is the touching hands' own velocity at
// the body plus the fitted correction: the fit only sees what still penetrates after the body's last frame of
// motion, so the correction alone would stop a body that moves along with the hand (a box thrown while the
// index still touches it, a box pushed by a moving palm) every frame. With the hand's velocity as the base, a
// body carried by a moving hand keeps its speed, and one under a still hand gets exactly the correction.
//
// A hand that holds one part of a jointed object does not push the other parts: its fingers around the lid
// also graze the base, and the base pushed by the hand that carries the lid hinged to it would be pushed by
// itself (the experiments saw such a base thrown metres). The parts stay free for the other hand.
StageReport fit_touched_bodies(const WorldModel& model, std::vector<Body>& bodies, std::vector<Joint>& joints,
                               const std::vector<HandSlot>& hands, HandBodyPairs& pairs,
                               const std::vector<uint32_t>& held, std::vector<uint32_t>& released,
                               BulletBackend& backend, const BodyBoxes& boxes, PoseFitScratch& scratch, double dt) {
  const WorldDef& def = model.def;
  std::vector<Vec3>& from = scratch.from;
  std::vector<Vec3>& to = scratch.to;
  std::vector<SkinContact>& pressed = scratch.pressed;
  std::vector<SkinContact>& overlap = scratch.overlap;
  constexpr double kUnbounded = std::numeric_limits<double>::infinity();
  std::vector<std::pair<uint32_t, uint32_t>>& held_groups = scratch.held_groups;  // (hand, group root) of every held body
  held_groups.clear();
  for (uint32_t bi : held) {
    const Body& b = bodies[bi];  // an unjointed held body is its own group and is not fitted
    held_groups.push_back({b.grasp.primary.index, group_root(bodies, joints, bi)});
    if (!b.grasp.secondary.is_null()) held_groups.push_back({b.grasp.secondary.index, group_root(bodies, joints, bi)});
  }
  auto holds_group_of = [&](uint32_t hand, uint32_t body) {
    const std::pair<uint32_t, uint32_t> key{hand, group_root(bodies, joints, body)};
    return std::find(held_groups.begin(), held_groups.end(), key) != held_groups.end();
  };
  int fitted = 0;
  for (uint32_t k : model.joint_order) bodies[joints[k].child].supported = false;  // only joints' children are
  // The touched bodies in slot order (the pairs are ordered by hand first), each with its pairs.
  auto& touched = scratch.touched;
  touched.clear();
  for (auto& entry : pairs)
    if (!entry.second.contacts.empty()) touched.push_back({entry.first.second, &entry});
  if (touched.size() > 1)  // (a list of one is sorted, and stable_sort would allocate its buffer for it)
    std::stable_sort(touched.begin(), touched.end(),
                     [](const auto& a, const auto& b) { return a.first < b.first; });
  for (size_t t = 0; t < touched.size();) {
    const uint32_t bi = touched[t].first;
    size_t end = t;
    while (end < touched.size() && touched[end].first == bi) ++end;
    Body& b = bodies[bi];
    const size_t first = t;
    t = end;
    if (!b.manipulable() || b.grasp.grasped || b.just_released) continue;
    from.clear();
    to.clear();
    BodyVelocity carried;
    // Only the overlap beyond the skin is bone pushing the body (WorldDef::skin_depth; 0: all of it).
    const double skin = def.skin_depth;
    const bool physical = def.push_model == PushModel::Physical || def.push_model == PushModel::Wrap;
    pressed.clear();
    overlap.clear();
    scratch.support.clear();
    if (physical && !b.jointed()) support_contacts(def, bodies, boxes, scratch.stop, b, scratch.support);
    const bool free_body = physical && !b.jointed();
    for (size_t e = first; e < end; ++e) {
      auto& entry = *touched[e].second;
      if (holds_group_of(entry.first.first, bi)) continue;
      const size_t before = from.size();
      const HandSlot& hand = hands[entry.first.first];
      const bool wrapping = physical && wraps(def, hand);
      const bool let_go = entry.second.let_go;
      const BodyVelocity body = let_go ? let_go_velocity(b, dt) : BodyVelocity{};
      for (const ParticleContact& c : entry.second.contacts) {
        if (c.depth <= 0) continue;
        if (wrapping && free_body && forms_grip(hand, c)) {
          // The overlap it leaves is the closing grip's depth, like a hold's: once the hand stops closing without a
          // grasp, it goes only as the hand moves into the body (moved_into), not at once as a jump.
          entry.second.let_go = true;
          continue;
        }
        if (physical) {
          // Every contact is pulp pressing and rubbing; the bone's overlap beyond the skin is removed below, unless
          // the hand is closing its grip (Wrap): then all of it is pulp, and its digits leave a free body alone
          // (forms_grip). A hand that let go of it removes only what it moved in this frame (moved_into).
          pressed.push_back(skin_contact(def, c, hand, dt, kPulpFriction, wrapping));
          if (c.depth > skin && !wrapping) {
            const double bone = let_go ? std::min(c.depth - skin, moved_into(def, hand, b, body, c, dt)) : c.depth - skin;
            if (bone > 0) overlap.push_back({c.point, c.normal, -c.normal * bone, kUnbounded, 0.0});
          }
          continue;
        }
        if (c.depth <= skin) {
          pressed.push_back(skin_contact(def, c, hand, dt, 0.0));
          continue;
        }
        from.push_back(c.point);
        to.push_back(c.point - c.normal * (c.depth - skin));  // where the surface must go to stop the penetration
      }
      if (physical) continue;
      const BodyVelocity v = hand.history.attached_body_velocity(b.pose.position);
      carried.linear += double(from.size() - before) * v.linear;
      carried.angular += double(from.size() - before) * v.angular;
    }
    if (physical) {
      if (pressed.empty()) continue;
      physical_push(def, bodies, joints, backend, boxes, scratch, b, dt);
    } else if (!from.empty()) {
      const BodyVelocity correction = velocity_from_motion(fit_rigid_motion(from, to), b.pose.position, dt);
      push_touched_body(def, bodies, joints, backend, b, b.pose, carried.linear / double(from.size()) + correction.linear,
                        carried.angular / double(from.size()) + correction.angular, dt);
    } else if (!pressed.empty()) {
      // Only pulp touches the body: it presses, and Bullet weighs the press against the body's support.
      const BodyVelocity v = skin_press(pressed, inverse_inertia(b), {b.linear, b.angular});
      push_touched_body(def, bodies, joints, backend, b, b.pose, v.linear, v.angular, dt);
    } else {
      continue;
    }
    ++fitted;
  }
  for (uint32_t bi : released) bodies[bi].just_released = false;
  released.clear();
  if (fitted == 0) return stage_skipped(SkipReason::NoFreeBodyTouched);
  return stage_work(fitted);
}

}  // namespace handsim
