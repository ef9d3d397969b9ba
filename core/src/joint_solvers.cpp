#include "joint_solvers.h"

#include "joint_solvers_internal.h"
#include "validate.h"

#include <Eigen/Eigenvalues>
#include <Eigen/SVD>

#include <algorithm>
#include <cmath>

namespace handsim {

using detail::RelativeTarget;
using detail::Stopwatch;

namespace {

constexpr double kTwoPi = 2.0 * M_PI;
// rho = sqrt(a^2 + b^2) below this fraction of sum w (|q_perp|^2 + |u_perp|^2) (an upper bound of 2 rho)
// is rounding noise: the hinge cost is flat.
constexpr double kFlatCost = 1e-12;

Mat3 skew(const Vec3& v) {
  Mat3 k;
  k << 0, -v.z(), v.y(), v.z(), 0, -v.x(), -v.y(), v.x(), 0;
  return k;
}

Mat3 rotation(const Vec3& axis, double angle) { return Eigen::AngleAxisd(angle, axis).toRotationMatrix(); }

// continuous_turns (JointSolveOptions::continuous): see below. Otherwise, the global minimum in the limits:
// the turn theta0 + 2 pi k nearest `previous` inside [lower, upper]; when no turn is inside, the limit where
// the cost A - rho cos(theta - theta0) is smaller (ties: the limit nearer `previous`). Distance to previous
// is convex in k, so clamping the unconstrained best k into the admissible range gives the admissible best.
double pick_turn(double theta0, double previous, double lower, double upper, bool continuous_turns,
                 bool& at_limit) {
  double k = std::round((previous - theta0) / kTwoPi);
  if (continuous_turns) {
    // The joint moves from `previous`: the shorter way round to the target, held at the stop on its side.
    const double theta = theta0 + kTwoPi * k;
    at_limit = theta < lower || theta > upper;
    return std::clamp(theta, lower, upper);
  }
  double k_min = std::ceil((lower - theta0) / kTwoPi);   // -inf when unlimited
  double k_max = std::floor((upper - theta0) / kTwoPi);  // +inf when unlimited
  at_limit = k_min > k_max;
  if (!at_limit) return theta0 + kTwoPi * std::clamp(k, k_min, k_max);
  double cos_lower = std::cos(lower - theta0), cos_upper = std::cos(upper - theta0);
  if (cos_lower != cos_upper) return cos_lower > cos_upper ? lower : upper;
  return std::abs(previous - lower) <= std::abs(previous - upper) ? lower : upper;
}

// One-dimensional Levenberg-Marquardt on E(x) = sum |r_k(x)|^2. `eval` returns the cost, g = J^T r and
// h = J^T J at x. Steps are clamped into [lower, upper] (a projected LM: valid for one variable because the
// clamped point is the minimizer of the damped quadratic model over the interval).
struct Eval1 {
  double cost, g, h;
};

template <class F>
JointSolveResult levenberg_marquardt_1d(F eval, double start, double lower, double upper, double h_min,
                                        int max_iterations) {
  JointSolveResult r;
  double x = detail::clamp_to(start, lower, upper);
  Eval1 e = eval(x);
  r.value = x;
  r.cost = e.cost;
  if (!(e.h > h_min)) {  // the cost does not depend on x (enough): keep the start
    r.termination = JointTermination::Degenerate;
    return r;
  }
  double mu = 1e-4 * e.h;  // start close to Gauss-Newton; grow on rejected steps
  r.termination = JointTermination::MaxIterations;
  while (r.iterations < max_iterations) {
    // Stationary relative to |J||r| (by Cauchy-Schwarz the largest |g| can be): the remaining step
    // |g|/h is below 1e-10 * rms residual / rms lever. This is also where a start on the cost maximum stops.
    if (std::abs(e.g) <= 1e-10 * std::sqrt(e.h * e.cost) || e.cost == 0) {
      r.termination = JointTermination::Converged;
      break;
    }
    ++r.iterations;
    const double trial = x - e.g / (e.h + mu);
    const double xn = detail::clamp_to(trial, lower, upper);
    if (xn == x) {  // the clamp ate the whole step (descent points out of the limits), or it is below 1 ulp
      r.termination = trial != xn ? JointTermination::AtLimit : JointTermination::Converged;
      break;
    }
    Eval1 en = eval(xn);
    if (en.cost > e.cost) {
      // A rejected step this small is the rounding floor of the cost (about sqrt(eps) * residual / lever
      // in x): no step can be told to improve it.
      if (std::abs(xn - x) <= 1e-12 * (1 + std::abs(x))) {
        r.termination = JointTermination::Converged;
        break;
      }
      mu = std::max(mu * 10, 1e-12 * e.h);
      continue;
    }
    double dx = xn - x;
    x = xn;
    e = en;
    mu *= 0.1;
    if (std::abs(dx) <= 1e-12 * (1 + std::abs(x))) {
      r.termination = (x == lower || x == upper) ? JointTermination::AtLimit : JointTermination::Converged;
      break;
    }
  }
  r.value = x;
  r.cost = e.cost;
  if (r.termination == JointTermination::MaxIterations && (x == lower || x == upper) &&
      (x == lower ? e.g > 0 : e.g < 0))
    r.termination = JointTermination::AtLimit;
  return r;
}

// Pieces of the hinge cost sum w |q_k - R(theta) u_k|^2 = A - 2 (alpha cos + beta sin), in closed form.
struct HingeTerms {
  double alpha, beta;  // the minimum is at atan2(beta, alpha)
  double lever2;       // sum w |u_perp|^2: how much the vertices turn with theta
  double target2;      // sum w |q_perp|^2
};

HingeTerms hinge_terms(const Vec3& a, const Mat3& r0, const RelativeTarget& t, const VertexMoments& m) {
  // q_k = Rs d_k + c, u_k = R0 d_k. sum w q^T M u = tr(Rs^T M R0 D2) + c^T M R0 D1.
  const Mat3 proj = Mat3::Identity() - a * a.transpose();
  const Mat3 k = skew(a);
  const Mat3 r0d2 = r0 * m.second;
  const Vec3 r0d1 = r0 * m.first;
  const Mat3 rst = t.rotation.transpose();
  HingeTerms h;
  h.alpha = (rst * proj * r0d2).trace() + t.offset.dot(proj * r0d1);    // sum w q_perp . u_perp
  h.beta = (rst * k * r0d2).trace() + t.offset.dot(k * r0d1);           // sum w q . (a x u)
  h.lever2 = (proj * r0d2 * r0.transpose()).trace();
  h.target2 = (rst * proj * t.rotation * m.second).trace() + 2 * t.offset.dot(proj * t.rotation * m.first) +
              m.weight_sum * t.offset.dot(proj * t.offset);
  return h;
}

double hinge_cost(const HingeFrame& f, const RelativeTarget& t, const VertexMoments& m, double theta) {
  Mat3 mm = t.rotation - rotation(f.axis_parent, theta) * f.rest.toRotationMatrix();
  return detail::rigid_cost(mm, t.offset, m);
}

void check_moments_about(const VertexMoments& m, const Vec3& about) {
  if (m.about != about || m.count < 1 || !(m.weight_sum > 0))
    validate::fail("moments", "must be computed (vertex_moments) about the joint's point on the child, " +
                                  validate::fmt(about) + ", got " + validate::fmt(m.about));
}

double sum_w(const JointVertices& v) {
  return v.weights.size() ? v.weights.sum() : double(v.points.cols());
}

}  // namespace

// ---------------------------------------------------------------------------------------------------
namespace detail {

RelativeTarget relative_target(const Pose& parent, const Pose& simulated, const Vec3& point_child,
                               const Vec3& point_parent) {
  Quat pinv = parent.orientation.conjugate();
  RelativeTarget t;
  t.rotation = (pinv * simulated.orientation).toRotationMatrix();
  t.offset = pinv * (simulated.orientation * point_child + (simulated.position - parent.position)) - point_parent;
  return t;
}

VertexPairs vertex_pairs(const JointVertices& v, const Vec3& about_child, const RelativeTarget& t,
                         const Quat& rest) {
  const Eigen::Index n = v.points.cols();
  const Eigen::Matrix3Xd d = v.points.colwise() - about_child;
  VertexPairs p;
  p.q = (t.rotation * d).colwise() + t.offset;
  p.u = rest.toRotationMatrix() * d;
  p.sqrt_w = v.weights.size() ? Eigen::VectorXd(v.weights.cwiseSqrt()) : Eigen::VectorXd::Ones(n);
  return p;
}

double rigid_cost(const Mat3& m, const Vec3& e, const VertexMoments& mo) {
  double c = (m.transpose() * m * mo.second).trace() + 2 * e.dot(m * mo.first) + mo.weight_sum * e.squaredNorm();
  return std::max(c, 0.0);  // the three terms can cancel below zero by rounding when the fit is perfect
}

double clamp_to(double x, double lower, double upper) { return std::min(std::max(x, lower), upper); }

void check_previous(double previous) { validate::finite(previous, "previous"); }

void check_vertices_about(const JointVertices& v, const Vec3& about) {
  check_moments_about(v.moments, about);
  if (v.points.cols() != v.moments.count || (v.weights.size() && v.weights.size() != v.points.cols()))
    validate::fail("vertices", "points, weights and moments disagree; build them with make_joint_vertices");
}

}  // namespace detail

// ---------------------------------------------------------------------------------------------------
// Frames.

HingeFrame make_hinge_frame(const HingeDef& d, const std::string& arg) {
  validate_joint(d, arg);
  HingeFrame f;
  f.pivot_parent = d.pivot_parent;
  f.pivot_child = d.pivot_child;
  f.axis_parent = d.axis_parent.stableNormalized();  // stable: (1e308, 0, 0) would overflow to 0
  f.rest = d.rest_orientation ? d.rest_orientation->normalized()
                              : Quat::FromTwoVectors(d.axis_child.stableNormalized(), f.axis_parent);
  f.lower = d.lower;
  f.upper = d.upper;
  return f;
}

SliderFrame make_slider_frame(const SliderDef& d, const std::string& arg) {
  validate_joint(d, arg);
  return {d.anchor_parent, d.axis.stableNormalized(), d.anchor_child, d.rest_orientation.normalized(), d.lower,
          d.upper};
}

BallFrame make_ball_frame(const BallDef& d, const std::string& arg) {
  validate_joint(d, arg);
  BallFrame f;
  f.pivot_parent = d.pivot_parent;
  f.pivot_child = d.pivot_child;
  f.rest = d.rest_orientation.normalized();
  if (d.cone_half_angle) {
    f.cone_axis = d.cone_axis.stableNormalized();
    f.cone_half_angle = *d.cone_half_angle;
  }
  return f;
}

FixedFrame make_fixed_frame(const FixedDef& d, const std::string& arg) {
  validate_joint(d, arg);
  return {validate::pose(d.relative, arg + ".relative")};
}

// ---------------------------------------------------------------------------------------------------
// Vertices.

VertexMoments vertex_moments(const Eigen::Matrix3Xd& points, const Eigen::VectorXd& weights, const Vec3& about) {
  if (points.cols() < 1) validate::fail("vertices", "need at least one vertex");
  if (!points.allFinite()) validate::fail("vertices", "must be finite");
  validate::finite(about, "about");
  if (weights.size() && weights.size() != points.cols())
    validate::fail("weights", "must be empty or hold one weight per vertex, got " +
                                  std::to_string(weights.size()) + " for " + std::to_string(points.cols()));
  if (weights.size() && (!weights.allFinite() || (weights.array() < 0).any()))
    validate::fail("weights", "must be finite and >= 0");
  VertexMoments m;
  m.about = about;
  m.count = int(points.cols());
  for (Eigen::Index k = 0; k < points.cols(); ++k) {
    double w = weights.size() ? weights[k] : 1.0;
    Vec3 d = points.col(k) - about;  // about the joint point: small numbers even for a far-away body frame
    m.weight_sum += w;
    m.first += w * d;
    m.second.noalias() += w * d * d.transpose();
  }
  if (!(m.weight_sum > 0)) validate::fail("weights", "must not all be zero");
  return m;
}

JointVertices make_joint_vertices(Eigen::Matrix3Xd points, Eigen::VectorXd weights, const Vec3& about) {
  JointVertices v;
  v.moments = vertex_moments(points, weights, about);
  v.points = std::move(points);
  v.weights = std::move(weights);
  return v;
}

// ---------------------------------------------------------------------------------------------------
// Hinge.

JointSolveResult solve_hinge_exact(const HingeFrame& f, const VertexMoments& m, const Pose& parent,
                                   const Pose& simulated, double previous, const JointSolveOptions& o) {
  Stopwatch clock;
  check_moments_about(m, f.pivot_child);
  detail::check_previous(previous);
  RelativeTarget t = detail::relative_target(parent, simulated, f.pivot_child, f.pivot_parent);
  HingeTerms h = hinge_terms(f.axis_parent, f.rest.toRotationMatrix(), t, m);
  double rho = std::hypot(h.alpha, h.beta);
  JointSolveResult r;
  bool no_lever = h.lever2 <= m.weight_sum * o.min_lever * o.min_lever;
  if (no_lever || rho <= kFlatCost * (h.lever2 + h.target2)) {
    r.value = detail::clamp_to(previous, f.lower, f.upper);
    r.termination = JointTermination::Degenerate;
  } else {
    bool at_limit = false;
    r.value = pick_turn(std::atan2(h.beta, h.alpha), previous, f.lower, f.upper, o.continuous, at_limit);
    r.termination = at_limit ? JointTermination::AtLimit : JointTermination::Converged;
  }
  r.cost = hinge_cost(f, t, m, r.value);
  r.seconds = clock.seconds();
  return r;
}

JointSolveResult solve_hinge_lm(const HingeFrame& f, const JointVertices& v, const Pose& parent,
                                const Pose& simulated, double previous, const JointSolveOptions& o) {
  Stopwatch clock;
  detail::check_vertices_about(v, f.pivot_child);
  detail::check_previous(previous);
  RelativeTarget t = detail::relative_target(parent, simulated, f.pivot_child, f.pivot_parent);
  detail::VertexPairs p = detail::vertex_pairs(v, f.pivot_child, t, f.rest);
  const Vec3 a = f.axis_parent;
  // r_k = sqrt(w)(q_k - R(theta) u_k), dr_k/dtheta = -sqrt(w) a x (R(theta) u_k).
  auto eval = [&](double theta) {
    const Mat3 rot = rotation(a, theta);
    Eval1 e{0, 0, 0};
    for (Eigen::Index k = 0; k < p.q.cols(); ++k) {
      Vec3 ru = rot * p.u.col(k);
      Vec3 res = p.sqrt_w[k] * (p.q.col(k) - ru);
      Vec3 jac = -p.sqrt_w[k] * a.cross(ru);
      e.cost += res.squaredNorm();
      e.g += jac.dot(res);
      e.h += jac.squaredNorm();
    }
    return e;
  };
  // h = sum w |u_perp|^2 whatever theta: the same lever test as the exact solver.
  double h_min = sum_w(v) * o.min_lever * o.min_lever;
  JointSolveResult r = levenberg_marquardt_1d(eval, previous, f.lower, f.upper, h_min, o.max_iterations);
  r.seconds = clock.seconds();
  return r;
}

// One dispatch for both 1-DOF joints: the three solvers of a joint kind share one signature.
template <class Frame, class ExactFn, class LmFn, class CeresFn>
JointSolveResult solve_1dof(JointSolver s, ExactFn exact, LmFn lm, [[maybe_unused]] CeresFn ceres,
                            const Frame& f, const JointVertices& v, const Pose& parent, const Pose& simulated,
                            double previous, const JointSolveOptions& o) {
  switch (s) {
    case JointSolver::Exact: return exact(f, v.moments, parent, simulated, previous, o);
    case JointSolver::Lm: return lm(f, v, parent, simulated, previous, o);
    case JointSolver::LmCeres:
#if HANDSIM_WITH_CERES
      return ceres(f, v, parent, simulated, previous, o);
#else
      validate::fail("solver", "LmCeres needs a build with HANDSIM_WITH_CERES", Status::Unsupported);
#endif
  }
  validate::fail("solver", "unknown joint solver " + std::to_string(int(s)));
}

#if HANDSIM_WITH_CERES
#define HANDSIM_CERES_OR_NULL(fn) fn
#else
#define HANDSIM_CERES_OR_NULL(fn) nullptr
#endif

JointSolveResult solve_hinge(JointSolver s, const HingeFrame& f, const JointVertices& v, const Pose& parent,
                             const Pose& simulated, double previous, const JointSolveOptions& o) {
  return solve_1dof(s, solve_hinge_exact, solve_hinge_lm, HANDSIM_CERES_OR_NULL(solve_hinge_lm_ceres), f, v,
                    parent, simulated, previous, o);
}

Pose hinge_child_pose(const HingeFrame& f, const Pose& parent, double theta) {
  Quat rel = (Quat(Eigen::AngleAxisd(theta, f.axis_parent)) * f.rest).normalized();
  Pose local{f.pivot_parent - rel * f.pivot_child, rel};
  return parent * local;
}

double hinge_angle(const HingeFrame& f, const Pose& parent, const Pose& child, double near) {
  Quat rel = parent.orientation.conjugate() * child.orientation * f.rest.conjugate();
  double theta0 = 2 * std::atan2(f.axis_parent.dot(rel.vec()), rel.w());  // twist about the axis
  return theta0 + kTwoPi * std::round((near - theta0) / kTwoPi);
}

double hinge_violation(const HingeFrame& f, const Pose& parent, const Pose& child, double length) {
  Vec3 gap = parent.transform(f.pivot_parent) - child.transform(f.pivot_child);
  Vec3 axis_p = parent.orientation * f.axis_parent;
  Vec3 axis_c = child.orientation * (f.rest.conjugate() * f.axis_parent);
  return gap.norm() + length * std::atan2(axis_p.cross(axis_c).norm(), axis_p.dot(axis_c));
}

// ---------------------------------------------------------------------------------------------------
// Slider. E(s) = sum w |q_k - u_k - s a|^2 with q_k - u_k = (Rs - R0) d_k + c, so
// dE/ds = 0 gives s = a . ((Rs - R0) D1 + W c) / W: the weighted mean displacement along the axis.

JointSolveResult solve_slider_exact(const SliderFrame& f, const VertexMoments& m, const Pose& parent,
                                    const Pose& simulated, double previous, const JointSolveOptions&) {
  Stopwatch clock;
  check_moments_about(m, f.anchor_child);
  detail::check_previous(previous);
  RelativeTarget t = detail::relative_target(parent, simulated, f.anchor_child, f.anchor_parent);
  const Mat3 mm = t.rotation - f.rest.toRotationMatrix();
  double s = f.axis.dot(t.offset) + f.axis.dot(mm * m.first) / m.weight_sum;
  JointSolveResult r;
  r.value = detail::clamp_to(s, f.lower, f.upper);  // exact: E is a convex parabola in s
  r.termination = r.value != s ? JointTermination::AtLimit : JointTermination::Converged;
  r.cost = detail::rigid_cost(mm, t.offset - r.value * f.axis, m);
  r.seconds = clock.seconds();
  return r;
}

JointSolveResult solve_slider_lm(const SliderFrame& f, const JointVertices& v, const Pose& parent,
                                 const Pose& simulated, double previous, const JointSolveOptions& o) {
  Stopwatch clock;
  detail::check_vertices_about(v, f.anchor_child);
  detail::check_previous(previous);
  RelativeTarget t = detail::relative_target(parent, simulated, f.anchor_child, f.anchor_parent);
  detail::VertexPairs p = detail::vertex_pairs(v, f.anchor_child, t, f.rest);
  const Vec3 a = f.axis;
  auto eval = [&](double s) {  // r_k = sqrt(w)(q_k - u_k - s a), dr_k/ds = -sqrt(w) a
    Eval1 e{0, 0, 0};
    for (Eigen::Index k = 0; k < p.q.cols(); ++k) {
      Vec3 res = p.sqrt_w[k] * (p.q.col(k) - p.u.col(k) - s * a);
      e.cost += res.squaredNorm();
      e.g -= p.sqrt_w[k] * a.dot(res);
      e.h += p.sqrt_w[k] * p.sqrt_w[k];
    }
    return e;
  };
  JointSolveResult r = levenberg_marquardt_1d(eval, previous, f.lower, f.upper, 0.0, o.max_iterations);
  r.seconds = clock.seconds();
  return r;
}

JointSolveResult solve_slider(JointSolver s, const SliderFrame& f, const JointVertices& v, const Pose& parent,
                              const Pose& simulated, double previous, const JointSolveOptions& o) {
  return solve_1dof(s, solve_slider_exact, solve_slider_lm, HANDSIM_CERES_OR_NULL(solve_slider_lm_ceres), f, v,
                    parent, simulated, previous, o);
}

Pose slider_child_pose(const SliderFrame& f, const Pose& parent, double s) {
  Pose local{f.anchor_parent + s * f.axis - f.rest * f.anchor_child, f.rest};
  return parent * local;
}

double slider_displacement(const SliderFrame& f, const Pose& parent, const Pose& child) {
  return f.axis.dot(parent.inverse_transform(child.transform(f.anchor_child)) - f.anchor_parent);
}

double slider_violation(const SliderFrame& f, const Pose& parent, const Pose& child, double length) {
  Vec3 x = parent.inverse_transform(child.transform(f.anchor_child)) - f.anchor_parent;
  Vec3 off_line = x - f.axis.dot(x) * f.axis;
  Quat rel = parent.orientation.conjugate() * child.orientation;
  return off_line.norm() + length * rel.angularDistance(f.rest);
}

// ---------------------------------------------------------------------------------------------------
// Ball.

namespace {

// argmax_R tr(R^T H) over rotations: Kabsch/Horn with the reflection fix (det = -1 flips the last axis).
Mat3 kabsch(const Mat3& h) {
  Eigen::JacobiSVD<Mat3> svd(h, Eigen::ComputeFullU | Eigen::ComputeFullV);
  Mat3 d = Mat3::Identity();
  d(2, 2) = (svd.matrixU() * svd.matrixV().transpose()).determinant() < 0 ? -1.0 : 1.0;
  return svd.matrixU() * d * svd.matrixV().transpose();
}

// Swing projected onto the cone (same great circle), then the twist about n that maximizes tr(R^T H) for
// that swing: with R = Sw T(phi), tr(T^T Sw^T H) = cos(phi) <I - n n^T, G> + sin(phi) <[n]x, G> + const.
Mat3 cone_project(const Mat3& r, const Mat3& h, const Vec3& n, double half_angle, bool& clamped) {
  Vec3 m = r * n;
  Vec3 cross = n.cross(m);
  double swing = std::atan2(cross.norm(), n.dot(m));
  clamped = swing > half_angle;
  if (!clamped) return r;
  // Exactly antipodal: every great circle is as near; take a fixed perpendicular so the result is defined.
  Vec3 axis = cross.norm() > 1e-12 ? Vec3(cross.normalized()) : Vec3(n.unitOrthogonal());
  Mat3 sw = rotation(axis, half_angle);
  Mat3 g = sw.transpose() * h;
  Mat3 proj = Mat3::Identity() - n * n.transpose();
  double phi = std::atan2(skew(n).cwiseProduct(g).sum(), proj.cwiseProduct(g).sum());
  return sw * rotation(n, phi);
}

}  // namespace

BallSolveResult solve_ball_exact(const BallFrame& f, const VertexMoments& m, const Pose& parent,
                                 const Pose& simulated, const Quat& previous, const JointSolveOptions& o) {
  Stopwatch clock;
  check_moments_about(m, f.pivot_child);
  Quat prev = validate::unit_quat(previous, "previous");
  RelativeTarget t = detail::relative_target(parent, simulated, f.pivot_child, f.pivot_parent);
  const Mat3 r0 = f.rest.toRotationMatrix();
  // H = sum w q_k u_k^T, q_k = Rs d_k + c, u_k = R0 d_k.
  const Mat3 h = t.rotation * m.second * r0.transpose() + t.offset * (r0 * m.first).transpose();
  Eigen::SelfAdjointEigenSolver<Mat3> spread(m.second);  // eigenvalues ascending
  const double lever2 = m.weight_sum * o.min_lever * o.min_lever;
  BallSolveResult res;
  Mat3 r;
  if (spread.eigenvalues()[2] <= lever2) {  // every vertex near the pivot: no rotation is observable
    r = prev.toRotationMatrix();
    res.termination = JointTermination::Degenerate;
  } else if (spread.eigenvalues()[1] <= lever2) {  // a rod through the pivot: its own twist is free
    Vec3 e = r0 * spread.eigenvectors().col(2);
    Vec3 target = h * e;  // the rod direction that maximizes tr(R^T H) when R e is all that matters
    r = prev.toRotationMatrix();
    if (target.norm() > 0) r = Quat::FromTwoVectors(r * e, target).toRotationMatrix() * r;
    res.termination = JointTermination::Degenerate;
  } else {
    r = kabsch(h);
  }
  if (f.cone_half_angle < M_PI) {
    bool clamped = false;
    r = cone_project(r, h, f.cone_axis, f.cone_half_angle, clamped);
    if (clamped) res.termination = JointTermination::AtLimit;
  }
  res.rotation = Quat(r).normalized();
  res.cost = detail::rigid_cost(t.rotation - res.rotation.toRotationMatrix() * r0, t.offset, m);
  res.seconds = clock.seconds();
  return res;
}

Pose ball_child_pose(const BallFrame& f, const Pose& parent, const Quat& rotation) {
  Quat rel = (rotation * f.rest).normalized();
  return parent * Pose{f.pivot_parent - rel * f.pivot_child, rel};
}

Quat ball_rotation(const BallFrame& f, const Pose& parent, const Pose& child) {
  return (parent.orientation.conjugate() * child.orientation * f.rest.conjugate()).normalized();
}

double ball_violation(const BallFrame& f, const Pose& parent, const Pose& child) {
  return (parent.transform(f.pivot_parent) - child.transform(f.pivot_child)).norm();
}

// ---------------------------------------------------------------------------------------------------
// Fixed.

Pose fixed_child_pose(const FixedFrame& f, const Pose& parent) { return parent * f.relative; }

double fixed_violation(const FixedFrame& f, const Pose& parent, const Pose& child, double length) {
  Pose want = parent * f.relative;
  return (want.position - child.position).norm() + length * want.orientation.angularDistance(child.orientation);
}

}  // namespace handsim
