// Joints in the world. Hard joints (the default) keep the child in reduced coordinates: the core owns the
// joint coordinate, integrates it under gravity when nobody holds the child, projects a push (eq. 2) onto
// it, and fits it to the hand when the child is grasped (the micro-simulator, eq. 4). The child is a
// kinematic body in Bullet, placed from its parent and its coordinate, so it can never leave the joint or
// pass a limit. Soft joints are Bullet constraints between two dynamic bodies: the baseline that shows the
// rubber-band effect.
#include "pose_fit.h"
#include "validate.h"
#include "world_impl.h"

#include <algorithm>
#include <cmath>
#include <functional>
#include <type_traits>

namespace handsim {
namespace {

// The child's model vertices for the micro-simulator (body frame): the corners of a box, the extreme
// points of round shapes, the points of a hull or mesh.
Eigen::Matrix3Xd model_vertices(const ShapeDef& s) {
  std::vector<Vec3> v;
  switch (s.type) {
    case ShapeType::Box:
      for (int k = 0; k < 8; ++k)
        v.push_back(s.half_extents.cwiseProduct(Vec3(k & 1 ? 1 : -1, k & 2 ? 1 : -1, k & 4 ? 1 : -1)));
      break;
    case ShapeType::Sphere:
    case ShapeType::Capsule:
      for (double y : {-s.half_height, s.half_height})
        for (int axis : {0, 2})
          for (double sign : {-1.0, 1.0}) v.push_back(Vec3(0, y, 0) + sign * s.radius * Vec3::Unit(axis));
      v.push_back(Vec3(0, s.half_height + s.radius, 0));
      v.push_back(Vec3(0, -s.half_height - s.radius, 0));
      break;
    default:
      v = s.points;
  }
  Eigen::Matrix3Xd m(3, v.size());
  for (size_t i = 0; i < v.size(); ++i) m.col(i) = v[i];
  return m;
}

Vec3 joint_point_on_child(const Joint& j) {
  switch (j.type) {
    case JointType::Hinge: return j.hinge.pivot_child;
    case JointType::Slider: return j.slider.anchor_child;
    case JointType::Ball: return j.ball.pivot_child;
    case JointType::Fixed: return j.fixed.relative.inverse().position;
  }
  return Vec3::Zero();
}

// The body's inertia about its centre of mass, world frame, at `orientation`.
Mat3 world_inertia(const Body& b, const Quat& orientation) {
  const Mat3 R = orientation.toRotationMatrix();
  return R * (b.mass * b.unit_inertia).asDiagonal() * R.transpose();
}

// One damped velocity update, with the damping taken implicitly: rate' = (rate + impulse) / (1 + k),
// k = h c / I. An explicit update diverges once k > 2, which a light lid with a stiff hinge reaches easily
// (a 0.5 g lid with 0.002 N m s damping has k ~ 11 at 240 Hz); the implicit one is stable for any k.
double implicit_damped(double rate, double impulse, double k) { return (rate + impulse) / (1 + k); }

double clamp_coordinate(double& value, double& rate, double lower, double upper) {
  // An inelastic stop: the rate into the limit is removed.
  if (value < lower) {
    const double over = lower - value;
    value = lower;
    rate = std::max(rate, 0.0);
    return over;
  }
  if (value > upper) {
    const double over = value - upper;
    value = upper;
    rate = std::min(rate, 0.0);
    return over;
  }
  return 0;
}

}  // namespace

Joint& World::Impl::joint(JointId id, const char* argument) { return checked_slot(joints, id, argument); }
const Joint& World::Impl::joint(JointId id, const char* argument) const {
  return const_cast<Impl*>(this)->joint(id, argument);
}

namespace {
// One step up a joint group: the parent of `body` along its hard joint, else its soft one; kWorldParent at
// the top. group_root walks it and add_joint refuses a joint that would make it a loop, so the walk ends.
uint32_t group_parent(const std::vector<Body>& bodies, const std::vector<Joint>& joints, uint32_t body) {
  const int j = bodies[body].hard_joint >= 0 ? bodies[body].hard_joint : bodies[body].soft_joint;
  return j < 0 ? kWorldParent : joints[j].parent;
}
}  // namespace

uint32_t group_root(const std::vector<Body>& bodies, const std::vector<Joint>& joints, uint32_t body) {
  for (uint32_t up = group_parent(bodies, joints, body); up != kWorldParent; up = group_parent(bodies, joints, body))
    body = up;
  return body;
}

namespace {
// The paper pipeline solves with Ceres LM whatever the joint asks for (when Ceres is built in).
JointSolver solver_of([[maybe_unused]] const WorldDef& def, const Joint& j) {  // def: only with Ceres
#if HANDSIM_WITH_CERES
  if (def.paper_pipeline) return JointSolver::LmCeres;
#endif
  return j.solver;
}

JointSolveOptions joint_options(const WorldDef& def) {
  JointSolveOptions o;
  o.max_iterations = def.joint_max_iterations;
  o.continuous = true;  // a hard joint moves continuously: never through a stop (see JointSolveOptions)
  return o;
}
}  // namespace

Pose parent_pose(const std::vector<Body>& bodies, const Joint& j) {
  return j.parent == kWorldParent ? Pose() : bodies[j.parent].pose;
}

namespace {
// hinge_child_pose(j.hinge, parent, theta), made again only when one of the numbers it reads differs in a bit
// from the last call's (Joint::hinge_memo).
Pose hinge_pose(const Joint& j, const Pose& parent, double theta) {
  BitKey<21> key;
  key.put(parent.position.data(), 3).put(parent.orientation.coeffs().data(), 4).put(&theta, 1);
  key.put(j.hinge.pivot_parent.data(), 3).put(j.hinge.axis_parent.data(), 3).put(j.hinge.pivot_child.data(), 3);
  key.put(j.hinge.rest.coeffs().data(), 4);
  return j.hinge_memo.get(key, [&] { return hinge_child_pose(j.hinge, parent, theta); });
}
}  // namespace

Pose joint_child_pose(const std::vector<Body>& bodies, const Joint& j) {
  const Pose p = parent_pose(bodies, j);
  switch (j.type) {
    case JointType::Hinge: return hinge_pose(j, p, j.value);
    case JointType::Slider: return slider_child_pose(j.slider, p, j.value);
    case JointType::Ball: return ball_child_pose(j.ball, p, j.rotation);
    case JointType::Fixed: return fixed_child_pose(j.fixed, p);
  }
  return p;
}

namespace {
// Where a hinge's or slider's child is at its coordinate `value` (an angle or an offset) on the parent pose `parent`.
Pose coordinate_child_pose(const Joint& j, const Pose& parent, double value) {
  return j.type == JointType::Hinge ? hinge_pose(j, parent, value) : slider_child_pose(j.slider, parent, value);
}
}  // namespace

// --- adding and removing ---

namespace {
constexpr double kTwoPi = 2.0 * M_PI;

// The hinge angle a pose implies when the joint is made: of the turns theta + 2 pi k inside [lower, upper],
// the one nearest 0 (limits [3 pi, 5 pi] and a child at its rest pose give 4 pi, not a jump to 3 pi);
// with no turn inside, the nearer limit.
double initial_hinge_angle(double theta, double lower, double upper) {
  const double k_min = std::ceil((lower - theta) / kTwoPi), k_max = std::floor((upper - theta) / kTwoPi);
  if (k_min > k_max) return std::clamp(theta, lower, upper);
  return theta + kTwoPi * std::clamp(std::round(-theta / kTwoPi), k_min, k_max);
}

// Which joint coordinate the current poses imply, inside the limits.
void read_coordinate(Joint& j, const Pose& parent, const Pose& child) {
  switch (j.type) {
    case JointType::Hinge:
      j.value = initial_hinge_angle(hinge_angle(j.hinge, parent, child, 0.0), j.hinge.lower, j.hinge.upper);
      break;
    case JointType::Slider:
      j.value = std::clamp(slider_displacement(j.slider, parent, child), j.slider.lower, j.slider.upper);
      break;
    case JointType::Ball: {
      BallSolveResult r = solve_ball_exact(j.ball, j.vertices.moments, parent, child, Quat::Identity());
      j.rotation = r.rotation;
      break;
    }
    case JointType::Fixed:
      break;
  }
}
}  // namespace

JointId World::Impl::add_joint(Joint j, BodyId parent_id, BodyId child_id, const std::string& arg) {
  Body& c = body(child_id, (arg + ".child").c_str());
  if (!parent_id.is_null()) body(parent_id, (arg + ".parent").c_str());
  if (c.declared != BodyMotion::Dynamic)
    validate::fail(arg + ".child", "must be a dynamic body (mass > 0, not kinematic)", Status::InvalidState);
#if !HANDSIM_WITH_CERES
  if (j.solver == JointSolver::LmCeres)
    validate::fail(arg + ".solver", "LmCeres needs a build with HANDSIM_WITH_CERES", Status::Unsupported);
#endif
  j.parent = parent_id.is_null() ? kWorldParent : parent_id.index;
  j.child = child_id.index;
  if (j.model == JointModel::Hard) {
    if (c.hard_joint >= 0)
      validate::fail(arg + ".child", "is already the child of a hard joint", Status::InvalidState);
  } else if (c.soft_joint >= 0 || c.hard_joint >= 0) {
    validate::fail(arg + ".child", "is already the child of a joint", Status::InvalidState);
  }
  // Walking up from the parent, through hard and soft joints alike (as group_root does), must not reach the
  // child, or the group would be a loop. Soft joints were not walked: two soft joints each the other's parent,
  // or a hard one closing a ring through a soft one, hung group_root (found by the fuzz driver, issue 22).
  for (uint32_t p = j.parent; p != kWorldParent; p = group_parent(bodies, joints, p))
    if (p == j.child) validate::fail(arg + ".parent", "is the child or a descendant of it: a loop", Status::InvalidState);
  j.vertices = make_joint_vertices(model_vertices(c.shape), Eigen::VectorXd(), joint_point_on_child(j));
  Vec3 lo, hi;
  shape_local_bounds(c.shape, lo, hi);
  j.length = 0.5 * (hi - lo).norm();
  read_coordinate(j, parent_pose(bodies, j), c.pose);

  // Everything validated: from here on the world changes.
  const uint32_t index = allocate_slot(joints, free_joint_slots);
  j.generation = joints[index].generation;
  j.alive = true;
  const int parent_backend = j.parent == kWorldParent ? -1 : bodies[j.parent].backend;
  if (j.model == JointModel::Hard) {
    c.hard_joint = int(index);
    if (!c.grasp.grasped) set_motion(*backend, *this, c, BodyMotion::Kinematic);
    if (parent_backend >= 0) backend->set_collision(parent_backend, c.backend, false);
    joints[index] = std::move(j);
    rebuild_joint_order();
    place_children(*this, joints, bodies, *backend);  // the child snaps onto its joint
  } else {
    switch (j.type) {
      case JointType::Hinge: j.constraint = backend->add_hinge(parent_backend, c.backend, j.hinge); break;
      case JointType::Slider: j.constraint = backend->add_slider(parent_backend, c.backend, j.slider); break;
      case JointType::Ball: j.constraint = backend->add_ball(parent_backend, c.backend, j.ball); break;
      case JointType::Fixed: j.constraint = backend->add_fixed(parent_backend, c.backend, j.fixed); break;
    }
    c.soft_joint = int(index);
    joints[index] = std::move(j);
  }
  return joint_id(index);
}

void World::Impl::rebuild_joint_order() {
  joint_order.clear();
  std::function<int(uint32_t)> depth = [&](uint32_t k) {
    const Joint& j = joints[k];
    if (j.parent == kWorldParent || bodies[j.parent].hard_joint < 0) return 0;
    return depth(uint32_t(bodies[j.parent].hard_joint)) + 1;
  };
  for (uint32_t k = 0; k < joints.size(); ++k)
    if (joints[k].alive && joints[k].model == JointModel::Hard) {
      joints[k].depth = depth(k);
      joint_order.push_back(k);
    }
  std::stable_sort(joint_order.begin(), joint_order.end(),
                   [&](uint32_t a, uint32_t b) { return joints[a].depth < joints[b].depth; });
}

// --- placing hard children ---

void place_children(const WorldModel& model, const std::vector<Joint>& joints, std::vector<Body>& bodies,
                    BulletBackend& backend) {
  for (uint32_t k : model.joint_order) {
    const Joint& j = joints[k];
    Body& c = bodies[j.child];
    const Pose p = parent_pose(bodies, j);
    c.pose = joint_child_pose(bodies, j);
    // The child's velocity: the parent's rigid motion plus the joint's own.
    const BodyVelocity carried = parent_motion(bodies, j, c.pose.position);
    Vec3 v = carried.linear, w = carried.angular;
    switch (j.type) {
      case JointType::Hinge: {
        const Vec3 a = p.orientation * j.hinge.axis_parent;
        w += j.rate * a;
        v += j.rate * a.cross(c.pose.position - p.transform(j.hinge.pivot_parent));
        break;
      }
      case JointType::Slider:
        v += j.rate * (p.orientation * j.slider.axis);
        break;
      case JointType::Ball:
        w += j.spin;
        v += j.spin.cross(c.pose.position - p.transform(j.ball.pivot_parent));
        break;
      case JointType::Fixed:
        break;
    }
    c.linear = v;
    c.angular = w;
    backend.move_kinematic(c.backend, c.pose);
  }
}

void replace_children(const WorldModel& model, const std::vector<Joint>& joints, const std::vector<Body>& bodies,
                      BulletBackend& backend) {
  for (uint32_t k : model.joint_order) backend.keep_kinematic(bodies[joints[k].child].backend);
}

void resave_children(const WorldModel& model, const std::vector<Joint>& joints, const std::vector<Body>& bodies,
                     BulletBackend& backend) {
  for (uint32_t k : model.joint_order) backend.resave_at_next_idle(bodies[joints[k].child].backend);
}

// --- free dynamics of hard joints (one substep) ---

namespace {
// [v]x: cross_matrix(v) * u == v.cross(u).
Mat3 cross_matrix(const Vec3& v) {
  Mat3 m;
  m << 0, -v.z(), v.y(), v.z(), 0, -v.x(), -v.y(), v.x(), 0;
  return m;
}
}  // namespace

bool integrates(const Joint& j, const Body& child) {
  return !child.grasp.grasped && j.type != JointType::Fixed;  // held: the hand decides (solve_joints)
}

bool joints_integrate(const WorldModel& model, const std::vector<Joint>& joints, const std::vector<Body>& bodies) {
  for (uint32_t k : model.joint_order)
    if (integrates(joints[k], bodies[joints[k].child])) return true;
  return false;
}

void integrate_joints(const WorldModel& model, std::vector<Joint>& joints, const std::vector<Body>& bodies, double h) {
  for (uint32_t k : model.joint_order) {
    Joint& j = joints[k];
    const Body& c = bodies[j.child];
    if (!integrates(j, c)) continue;
    const Vec3 g = c.supported ? Vec3::Zero() : model.def.gravity;
    const Pose p = parent_pose(bodies, j);
    const Pose now = joint_child_pose(bodies, j);
    const double m = c.mass;
    if (j.type == JointType::Hinge) {
      // One rotational DOF: I_axis theta'' = torque of gravity about the axis - damping theta'.
      const Vec3 a = p.orientation * j.hinge.axis_parent;
      const Vec3 r = now.position - p.transform(j.hinge.pivot_parent);
      const double inertia = a.dot(world_inertia(c, now.orientation) * a) + m * (r.squaredNorm() - std::pow(r.dot(a), 2));
      const double torque = a.dot(r.cross(m * g));
      j.rate = implicit_damped(j.rate, h * torque / inertia, h * j.damping / inertia);
      const double before = j.value;
      j.value += h * j.rate;
      clamp_coordinate(j.value, j.rate, j.hinge.lower, j.hinge.upper);
      if (stopped_by_parent(bodies, j, now, hinge_pose(j, p, j.value))) j.value = before, j.rate = 0;
    } else if (j.type == JointType::Slider) {
      const Vec3 a = p.orientation * j.slider.axis;
      j.rate = implicit_damped(j.rate, h * g.dot(a), h * j.damping / m);
      const double before = j.value;
      j.value += h * j.rate;
      clamp_coordinate(j.value, j.rate, j.slider.lower, j.slider.upper);
      if (stopped_by_parent(bodies, j, now, slider_child_pose(j.slider, p, j.value))) j.value = before, j.rate = 0;
    } else {
      // Three rotational DOFs about the pivot: Euler's equations with the inertia about the pivot.
      const Vec3 r = now.position - p.transform(j.ball.pivot_parent);
      const Mat3 inertia = world_inertia(c, now.orientation) + m * (r.squaredNorm() * Mat3::Identity() - r * r.transpose());
      // Implicit in the damping (for the same reason as implicit_damped) and in the gyroscopic term, by one
      // Newton step on I (w' - w) + h (w' x I w' + c w' - tau_gravity) = 0 (the linearisation Bullet's
      // implicit gyroscopic solver uses). The explicit gyroscopic term gained energy every substep: the fuzz
      // driver (issue 22 item 2) spun a ball child from 35 to 1e19 rad/s in 300 frames.
      const Vec3 momentum = inertia * j.spin;
      const Mat3 jacobian = inertia + h * (cross_matrix(j.spin) * inertia - cross_matrix(momentum)) +
                            h * j.damping * Mat3::Identity();
      const Vec3 residual = h * (j.spin.cross(momentum) + j.damping * j.spin - r.cross(m * g));
      j.spin -= jacobian.partialPivLu().solve(residual);
      const Quat turn(Eigen::AngleAxisd(h * j.spin.norm(), j.spin.normalized()));
      const Quat world_rel = j.spin.norm() > 0 ? turn : Quat::Identity();
      Quat next = (p.orientation.conjugate() * world_rel * p.orientation * j.rotation).normalized();
      if (j.ball.cone_half_angle < M_PI) {
        // Project onto the cone (exact solver on the free pose) and keep only the motion that remains.
        const BallSolveResult r2 =
            solve_ball_exact(j.ball, j.vertices.moments, p, ball_child_pose(j.ball, p, next), j.rotation);
        if (r2.termination == JointTermination::AtLimit) {
          next = r2.rotation;
          j.spin = rotation_vector(p.orientation * next * (p.orientation * j.rotation).conjugate()) / h;
        }
      }
      if (stopped_by_parent(bodies, j, now, ball_child_pose(j.ball, p, next))) {
        j.spin = Vec3::Zero();
        continue;
      }
      j.rotation = next;
    }
  }
}

// --- soft joints: a grasped child chases its hand with a velocity, the constraint pulls back ---

void drive_soft_children(const std::vector<uint32_t>& held, std::vector<Body>& bodies,
                         const std::vector<HandSlot>& hands, BulletBackend& backend, double h) {
  for (uint32_t bi : held) {
    Body& b = bodies[bi];
    if (b.soft_joint < 0) continue;
    const Pose target = hands[b.grasp.primary.index].palm * b.grasp.primary_relative;
    b.linear = (target.position - b.pose.position) / h;
    b.angular = rotation_vector(target.orientation * b.pose.orientation.conjugate()) / h;
    backend.write(b.backend, b.pose, b.linear, b.angular);
  }
}

// --- the micro-simulator (eq. 4) and the projection of a push ---

namespace {
void record(Joint& j, const JointSolveResult& r) {
  j.last = r;
  j.solved = true;
}
void record(Joint& j, const BallSolveResult& r) {
  j.last = {0.0, r.cost, r.iterations, r.termination, r.seconds};
  j.solved = true;
}
}  // namespace

// Where the hand wants the child (`simulated`) -> the nearest coordinate (eq. 4), with the rate that gets
// there over dt. A pushed child gets only the rate, so the push acts like a velocity and gravity and limits
// still apply (project_push); a grasped child is set there at once (solve_grasped).
void project_push(const WorldDef& def, const std::vector<Body>& bodies, Joint& j, const Pose& simulated, double dt) {
  const Pose p = parent_pose(bodies, j);
  const JointSolveOptions o = joint_options(def);
  switch (j.type) {
    case JointType::Hinge:
    case JointType::Slider: {
      const JointSolver solver = solver_of(def, j);
      const JointSolveResult r = j.type == JointType::Hinge
                                     ? solve_hinge(solver, j.hinge, j.vertices, p, simulated, j.value, o)
                                     : solve_slider(solver, j.slider, j.vertices, p, simulated, j.value, o);
      j.rate = (r.value - j.value) / dt;
      record(j, r);
      break;
    }
    case JointType::Ball: {
      const BallSolveResult r = solve_ball_exact(j.ball, j.vertices.moments, p, simulated, j.rotation, o);
      j.spin = rotation_vector(p.orientation * r.rotation * (p.orientation * j.rotation).conjugate()) / dt;
      j.solved_rotation = r.rotation;
      record(j, r);
      break;
    }
    case JointType::Fixed:
      break;
  }
}

void solve_grasped(const WorldDef& def, const std::vector<Body>& bodies, Joint& j, const Pose& simulated, double dt) {
  project_push(def, bodies, j, simulated, dt);
  if (!j.solved) return;
  const Pose p = parent_pose(bodies, j);
  if (j.type == JointType::Ball) {
    if (stopped_by_parent(bodies, j, joint_child_pose(bodies, j), ball_child_pose(j.ball, p, j.solved_rotation))) {
      j.spin = Vec3::Zero();
      return;
    }
    j.rotation = j.solved_rotation;  // the solved rotation itself (re-deriving it from spin * dt would round)
  } else {
    const bool coordinate = j.type == JointType::Hinge || j.type == JointType::Slider;
    const Pose now = joint_child_pose(bodies, j);
    if (coordinate && stopped_by_parent(bodies, j, now, coordinate_child_pose(j, p, j.last.value))) {
      j.rate = 0;
      return;
    }
    j.value = j.last.value;
  }
}

BodyVelocity parent_motion(const std::vector<Body>& bodies, const Joint& j, const Vec3& point) {
  if (j.parent == kWorldParent) return {};
  const Body& pb = bodies[j.parent];
  return {pb.linear + pb.angular.cross(point - pb.pose.position), pb.angular};
}

Vec3 coordinate_motion(const std::vector<Body>& bodies, const Joint& j, const Vec3& point) {
  const Pose p = parent_pose(bodies, j);
  switch (j.type) {
    case JointType::Hinge: return (p.orientation * j.hinge.axis_parent).cross(point - p.transform(j.hinge.pivot_parent));
    case JointType::Slider: return p.orientation * j.slider.axis;
    case JointType::Ball:
    case JointType::Fixed: break;
  }
  return Vec3::Zero();
}

void shift_coordinate(const std::vector<Body>& bodies, Joint& j, double step) {
  const bool hinge = j.type == JointType::Hinge;
  if (!hinge && j.type != JointType::Slider) return;
  const Pose now = joint_child_pose(bodies, j);
  double value = j.value + step, rate = 0;  // a displacement gives no rate
  clamp_coordinate(value, rate, hinge ? j.hinge.lower : j.slider.lower, hinge ? j.hinge.upper : j.slider.upper);
  const Pose p = parent_pose(bodies, j);
  // As a grasped child's solve (solve_grasped): the parent's surface stops the step.
  if (!stopped_by_parent(bodies, j, now, coordinate_child_pose(j, p, value))) j.value = value;
}

namespace {

// A child let go of in this step leaves with its hand's motion at it over velocity_window_s (the palm's least-squares
// slope), less its parent's, on its joint, as a released free body leaves with its hand's velocity (Grasps::end_grasp).
// The held solve's rate is one step's: the hand's last step over dt, in which one tracker jump of the grip reads
// jump / dt (confidence2's lid, lifted 5.8 deg in the last 30 Hz frame before its release: 175 deg/s, against 28 deg/s
// over the 120 Hz frame before the same release; docs/grasp.md "Under Wrap", frame rates).
void leave_with_hand(const WorldDef& def, const std::vector<Body>& bodies, Joint& j, const HandSlot& hand, double dt) {
  const Pose now = joint_child_pose(bodies, j);
  const BodyVelocity v = hand.history.attached_body_velocity(now.position);
  const BodyVelocity carried = parent_motion(bodies, j, now.position);
  project_push(def, bodies, j, advanced(now, v.linear - carried.linear, v.angular - carried.angular, dt), dt);
}

void read_soft_joint(const std::vector<Body>& bodies, Joint& j) {
  const Pose p = parent_pose(bodies, j), c = bodies[j.child].pose;
  switch (j.type) {
    case JointType::Hinge: j.value = hinge_angle(j.hinge, p, c, j.value); break;
    case JointType::Slider: j.value = slider_displacement(j.slider, p, c); break;
    case JointType::Ball: j.rotation = ball_rotation(j.ball, p, c); break;
    case JointType::Fixed: break;
  }
}
}  // namespace

// --- line 19 of Algorithm 1: grasped children of hard joints get their coordinate from the hand ---
StageReport solve_joints(const WorldModel& model, std::vector<Joint>& joints, std::vector<Body>& bodies,
                         const std::vector<HandSlot>& hands, BulletBackend& backend,
                         const std::vector<uint32_t>& letting_go, double dt) {
  int live = 0;
  for (uint32_t k : model.joint_order) {
    Joint& j = joints[k];
    const Body& c = bodies[j.child];
    if (!c.grasp.grasped) continue;
    const HandSlot& h = hands[c.grasp.primary.index];
    solve_grasped(model.def, bodies, j, h.palm * c.grasp.primary_relative, dt);
    if (c.grasp.secondary.is_null() && std::find(letting_go.begin(), letting_go.end(), j.child) != letting_go.end())
      leave_with_hand(model.def, bodies, j, h, dt);
  }
  if (!model.joint_order.empty()) place_children(model, joints, bodies, backend);
  for (Joint& j : joints) {
    if (!j.alive) continue;
    ++live;
    if (j.model == JointModel::Soft) read_soft_joint(bodies, j);
  }
  if (live == 0) return stage_skipped(SkipReason::NoJoints);
  return stage_work(live);
}

// --- public API ---

namespace {
// The parts every joint definition shares; `frame` is the compiled frame (make_*_frame).
template <class Def, class Frame>
Joint joint_from(JointType type, const Def& d, Frame JointSlotModel::*slot, Frame frame) {
  Joint j;
  j.type = type;
  j.model = d.model;
  j.*slot = std::move(frame);
  if constexpr (!std::is_same_v<Def, FixedDef>) {
    j.solver = d.solver;
    j.damping = d.damping;
  }
  return j;
}
}  // namespace

JointId World::add_joint(const HingeDef& d) {
  const auto held = lock();
  Joint j = joint_from(JointType::Hinge, d, &Joint::hinge, make_hinge_frame(d, "hinge"));
  return impl_->add_joint(std::move(j), d.parent, d.child, "hinge");
}

JointId World::add_joint(const SliderDef& d) {
  const auto held = lock();
  Joint j = joint_from(JointType::Slider, d, &Joint::slider, make_slider_frame(d, "slider"));
  return impl_->add_joint(std::move(j), d.parent, d.child, "slider");
}

JointId World::add_joint(const BallDef& d) {
  const auto held = lock();
  Joint j = joint_from(JointType::Ball, d, &Joint::ball, make_ball_frame(d, "ball"));
  return impl_->add_joint(std::move(j), d.parent, d.child, "ball");
}

JointId World::add_joint(const FixedDef& d) {
  const auto held = lock();
  Joint j = joint_from(JointType::Fixed, d, &Joint::fixed, make_fixed_frame(d, "fixed"));
  return impl_->add_joint(std::move(j), d.parent, d.child, "fixed");
}

void World::remove_joint(JointId id) {
  const auto held = lock();
  Impl& w = *impl_;
  Joint& j = w.joint(id);
  Body& c = w.bodies[j.child];
  if (j.model == JointModel::Hard) {
    c.hard_joint = -1;
    if (j.parent != kWorldParent) w.backend->set_collision(w.bodies[j.parent].backend, c.backend, true);
    // The child flies on with the velocity the joint gave it (place_children keeps it current).
    if (!c.grasp.grasped) {
      set_motion(*w.backend, w, c, BodyMotion::Dynamic);
      w.backend->write(c.backend, c.pose, c.linear, c.angular);
    }
  } else {
    w.backend->remove_constraint(j.constraint);
    c.soft_joint = -1;
  }
  release_slot(w.joints, w.free_joint_slots, id.index);
  w.rebuild_joint_order();
}

bool World::contains(JointId id) const {
  const auto held = lock();
  return !id.is_null() && id.index < impl_->joints.size() && impl_->joints[id.index].alive &&
         impl_->joints[id.index].generation == id.generation;
}

std::vector<JointId> World::joints() const {
  const auto held = lock();
  std::vector<JointId> out;
  for (uint32_t k = 0; k < impl_->joints.size(); ++k)
    if (impl_->joints[k].alive) out.push_back(impl_->joint_id(k));
  return out;
}

JointState World::joint_state(JointId id) const {
  const auto held = lock();
  const Impl& w = *impl_;
  const Joint& j = w.joint(id);
  JointState s;
  s.type = j.type;
  s.model = j.model;
  s.solver = j.solver;
  s.parent = j.parent == kWorldParent ? BodyId{} : w.body_id(j.parent);
  s.child = w.body_id(j.child);
  s.value = j.value;
  s.rate = j.rate;
  s.rotation = j.rotation;
  const Pose p = parent_pose(w.bodies, j), c = w.bodies[j.child].pose;
  switch (j.type) {
    case JointType::Hinge: {
      s.anchor = p.transform(j.hinge.pivot_parent);
      s.axis = p.orientation * j.hinge.axis_parent;
      s.lower = j.hinge.lower;
      s.upper = j.hinge.upper;
      s.violation = hinge_violation(j.hinge, p, c, j.length);
      const double theta = hinge_angle(j.hinge, p, c, j.value);
      s.overshoot = std::max({0.0, j.hinge.lower - theta, theta - j.hinge.upper});
      break;
    }
    case JointType::Slider: {
      s.anchor = p.transform(j.slider.anchor_parent);
      s.axis = p.orientation * j.slider.axis;
      s.lower = j.slider.lower;
      s.upper = j.slider.upper;
      s.violation = slider_violation(j.slider, p, c, j.length);
      const double d = slider_displacement(j.slider, p, c);
      s.overshoot = std::max({0.0, j.slider.lower - d, d - j.slider.upper});
      break;
    }
    case JointType::Ball: {
      s.anchor = p.transform(j.ball.pivot_parent);
      s.axis = p.orientation * j.ball.cone_axis;
      s.lower = 0;
      s.upper = j.ball.cone_half_angle;
      s.violation = ball_violation(j.ball, p, c);
      if (j.ball.cone_half_angle < M_PI) {
        const Vec3 axis = j.ball.cone_axis, swung = ball_rotation(j.ball, p, c) * axis;
        const double swing = std::atan2(axis.cross(swung).norm(), axis.dot(swung));
        s.overshoot = std::max(0.0, swing - j.ball.cone_half_angle);
      }
      break;
    }
    case JointType::Fixed:
      s.anchor = (p * j.fixed.relative).position;
      s.lower = s.upper = 0;
      s.violation = fixed_violation(j.fixed, p, c, j.length);
      break;
  }
  s.solved = j.solved;
  s.cost = j.last.cost;
  s.iterations = j.last.iterations;
  s.termination = j.last.termination;
  s.solve_seconds = j.last.seconds;
  return s;
}

void World::set_joint_value(JointId id, double value) {
  const auto held = lock();
  Impl& w = *impl_;
  Joint& j = w.joint(id);
  validate::finite(value, "value");
  if (j.type != JointType::Hinge && j.type != JointType::Slider)
    validate::fail("joint", "only a hinge or a slider has a single coordinate", Status::InvalidState);
  const double lower = j.type == JointType::Hinge ? j.hinge.lower : j.slider.lower;
  const double upper = j.type == JointType::Hinge ? j.hinge.upper : j.slider.upper;
  j.value = std::clamp(value, lower, upper);
  j.rate = 0;
  w.forget_body_paths();
  if (j.model == JointModel::Hard) {
    place_children(w, w.joints, w.bodies, *w.backend);
    return;
  }
  Body& c = w.bodies[j.child];
  c.pose = c.synced_pose = joint_child_pose(w.bodies, j);
  c.linear = c.angular = Vec3::Zero();
  w.backend->write(c.backend, c.pose, c.linear, c.angular);
}

}  // namespace handsim
