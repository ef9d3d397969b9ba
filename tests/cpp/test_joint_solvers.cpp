// Analytic tests of the micro-simulator solvers (joint_solvers.h). References are computed independently
// of the solver's moment algebra: per vertex, in long double, by dense search + Newton polish.
#include "joint_solvers.h"

#include <gtest/gtest.h>

#include <cmath>
#include <random>

namespace handsim {
namespace {

using LD = long double;
using Vec3L = Eigen::Matrix<LD, 3, 1>;
using Mat3L = Eigen::Matrix<LD, 3, 3>;

constexpr double kPi = M_PI;
constexpr double kDeg = M_PI / 180.0;

struct Rng {
  std::mt19937_64 gen;
  explicit Rng(uint64_t seed) : gen(seed) {}
  double uniform(double lo, double hi) { return std::uniform_real_distribution<double>(lo, hi)(gen); }
  Vec3 vec(double half) { return Vec3(uniform(-half, half), uniform(-half, half), uniform(-half, half)); }
  Vec3 unit() {
    Vec3 v;
    do v = vec(1); while (v.norm() < 0.1 || v.norm() > 1);
    return v.normalized();
  }
  Quat quat() { return Quat(Eigen::AngleAxisd(uniform(-kPi, kPi), unit())); }
  Pose pose(double half) { return {vec(half), quat()}; }
  Eigen::Matrix3Xd points(int n, const Vec3& center, double half) {
    Eigen::Matrix3Xd p(3, n);
    for (int k = 0; k < n; ++k) p.col(k) = center + vec(half);
    return p;
  }
};

Pose small_motion(Rng& rng, double metres, double radians) {
  return {rng.vec(metres), Quat(Eigen::AngleAxisd(rng.uniform(0, radians), rng.unit()))};
}

// Target q_k and rest model u_k in the parent frame about the parent pivot, in long double, vertex by vertex.
struct PairsL {
  std::vector<Vec3L> q, u;
  std::vector<LD> w;
};

PairsL pairs_ld(const Vec3& pivot_parent, const Vec3& pivot_child, const Quat& rest,
                const Eigen::Matrix3Xd& pts, const Pose& parent, const Pose& sim) {
  Mat3L rp = parent.orientation.cast<LD>().toRotationMatrix();
  Mat3L rs = sim.orientation.cast<LD>().toRotationMatrix();
  Mat3L r0 = rest.cast<LD>().toRotationMatrix();
  PairsL out;
  for (int k = 0; k < pts.cols(); ++k) {
    Vec3L v = pts.col(k).cast<LD>();
    Vec3L world = rs * v + sim.position.cast<LD>();
    out.q.push_back(rp.transpose() * (world - parent.position.cast<LD>()) - pivot_parent.cast<LD>());
    out.u.push_back(r0 * (v - pivot_child.cast<LD>()));
    out.w.push_back(1);
  }
  return out;
}

// Hinge cost and its first two derivatives in long double, from the vertices.
void hinge_cost_ld(const PairsL& p, const Vec3& axis, LD th, LD& f, LD& df, LD& ddf) {
  Vec3L a = axis.cast<LD>();
  LD c = std::cos(th), s = std::sin(th);
  f = df = ddf = 0;
  for (size_t k = 0; k < p.q.size(); ++k) {
    Vec3L u = p.u[k], up = u - a.dot(u) * a, au = a.cross(u);
    Vec3L ru = c * up + s * au + a.dot(u) * a;
    f += p.w[k] * (p.q[k] - ru).squaredNorm();
    df += -2 * p.w[k] * p.q[k].dot(-s * up + c * au);
    ddf += -2 * p.w[k] * p.q[k].dot(-c * up - s * au);
  }
}

// Global minimizer over (-pi, pi]: 720-sample search, then Newton polish.
LD hinge_reference(const PairsL& p, const Vec3& axis) {
  LD best = 0, best_f = INFINITY, f, df, ddf;
  for (int i = 0; i < 720; ++i) {
    LD th = -kPi + 2 * kPi * i / 720.0L;
    hinge_cost_ld(p, axis, th, f, df, ddf);
    if (f < best_f) best_f = f, best = th;
  }
  for (int it = 0; it < 30; ++it) {
    hinge_cost_ld(p, axis, best, f, df, ddf);
    if (ddf <= 0) break;
    best -= df / ddf;
  }
  return best;
}

// sum_k |A v_k - B v_k|^2 in double, straight from the vertices.
double pose_cost(const Eigen::Matrix3Xd& pts, const Pose& a, const Pose& b) {
  double sum = 0;
  for (int k = 0; k < pts.cols(); ++k) sum += (a.transform(pts.col(k)) - b.transform(pts.col(k))).squaredNorm();
  return sum;
}

double wrap(double x) { return std::remainder(x, 2 * kPi); }

// A random hinge with N vertices around the child pivot; the simulated pose is a hinge pose at theta_true
// moved by a small rigid motion (so the fit is not exact).
struct HingeCase {
  HingeFrame frame;
  JointVertices verts;
  Pose parent, sim;
  double theta_true;
};

HingeCase random_hinge(Rng& rng, int n, double noise_m, double noise_rad, const Vec3& offset = Vec3::Zero()) {
  HingeDef d;
  d.parent = {1, 1};
  d.child = {2, 1};
  d.pivot_parent = offset + rng.vec(0.2);
  d.pivot_child = offset + rng.vec(0.2);
  d.axis_parent = rng.unit();
  d.axis_child = rng.unit();
  HingeCase c;
  c.frame = make_hinge_frame(d);
  c.verts = make_joint_vertices(rng.points(n, d.pivot_child + rng.vec(0.1), 0.1), {}, d.pivot_child);
  c.parent = rng.pose(1);
  c.parent.position += offset;
  c.theta_true = rng.uniform(-kPi, kPi);
  Pose exact = hinge_child_pose(c.frame, c.parent, c.theta_true);
  Pose m = small_motion(rng, noise_m, noise_rad);
  c.sim = {exact.position + m.position, (m.orientation * exact.orientation).normalized()};
  return c;
}

LD reference_of(const HingeCase& c) {
  return hinge_reference(pairs_ld(c.frame.pivot_parent, c.frame.pivot_child, c.frame.rest, c.verts.points,
                                  c.parent, c.sim),
                         c.frame.axis_parent);
}

// ------------------------------------------------------------------------------------------- hinge exact

TEST(HingeExact, MatchesLongDoubleReferenceOnRandomPoses) {
  Rng rng(42);
  double worst = 0;
  for (int trial = 0; trial < 100; ++trial) {
    HingeCase c = random_hinge(rng, 64, 0.01, 0.2);
    LD ref = reference_of(c);
    JointSolveResult r = solve_hinge_exact(c.frame, c.verts.moments, c.parent, c.sim, double(ref) + 0.5);
    ASSERT_EQ(r.termination, JointTermination::Converged);
    worst = std::max(worst, std::abs(wrap(r.value - double(ref))));
    EXPECT_EQ(r.iterations, 0);
  }
  EXPECT_LE(worst, 1e-12);
}

TEST(HingeExact, NoiseFreeTargetRecoversAngleWithZeroCost) {
  Rng rng(7);
  for (int trial = 0; trial < 20; ++trial) {
    HingeCase c = random_hinge(rng, 16, 0, 0);
    JointSolveResult r = solve_hinge_exact(c.frame, c.verts.moments, c.parent, c.sim, c.theta_true);
    EXPECT_NEAR(r.value, c.theta_true, 1e-12);
    EXPECT_LE(r.cost, 1e-20);
  }
}

TEST(HingeExact, CostMatchesVertexSum) {
  Rng rng(8);
  HingeCase c = random_hinge(rng, 64, 0.02, 0.3);
  JointSolveResult r = solve_hinge_exact(c.frame, c.verts.moments, c.parent, c.sim, 0);
  LD f, df, ddf;
  hinge_cost_ld(pairs_ld(c.frame.pivot_parent, c.frame.pivot_child, c.frame.rest, c.verts.points, c.parent, c.sim),
                c.frame.axis_parent, r.value, f, df, ddf);
  EXPECT_NEAR(r.cost, double(f), 1e-12 * double(f));
  EXPECT_GT(ddf, 0);  // a minimum, not a maximum
}

// Hinge about X through the origin, identity rest, one vertex ring: target = the hinge pose at `deg`.
struct SimpleHinge {
  HingeFrame frame;
  JointVertices verts;
  Pose parent;
  explicit SimpleHinge(double lower = -kUnlimited, double upper = kUnlimited) {
    HingeDef d;
    d.parent = {1, 1};
    d.child = {2, 1};
    d.lower = lower;
    d.upper = upper;
    frame = make_hinge_frame(d);
    Eigen::Matrix3Xd p(3, 4);
    p << 0, 0.1, 0.2, 0.3,  //
        0.1, 0, -0.1, 0.05,  //
        0, 0.1, 0.05, -0.1;
    verts = make_joint_vertices(p, {}, Vec3::Zero());
  }
  Pose target(double deg) const { return hinge_child_pose(frame, parent, deg * kDeg); }
  JointSolveResult exact(double deg, double previous_deg) const {
    return solve_hinge_exact(frame, verts.moments, parent, target(deg), previous_deg * kDeg);
  }
};

TEST(HingeExact, UnlimitedKeepsCountingTurns) {
  SimpleHinge h;
  EXPECT_NEAR(h.exact(30, 3 * 360 + 10).value, (3 * 360 + 30) * kDeg, 1e-12);
  EXPECT_NEAR(h.exact(30, -2 * 360).value, (30 - 2 * 360) * kDeg, 1e-12);
  // Antipodal-ish: previous at 179 deg, target at -179 deg: the nearer turn is +181 deg, not -179.
  EXPECT_NEAR(h.exact(-179, 179).value, 181 * kDeg, 1e-12);
  EXPECT_NEAR(h.exact(179, -179).value, -181 * kDeg, 1e-12);
}

TEST(HingeExact, FullTurnLimitsUnwrapInsideTheRange) {
  SimpleHinge h(0, 2 * kPi);
  JointSolveResult r = h.exact(-10, 300);  // -10 deg is outside; 350 deg is the same pose and inside
  EXPECT_NEAR(r.value, 350 * kDeg, 1e-12);
  EXPECT_EQ(r.termination, JointTermination::Converged);
  SimpleHinge g(-kPi, kPi);
  EXPECT_NEAR(g.exact(179, -170).value, 179 * kDeg, 1e-12);  // -181 would be nearer but is outside
}

TEST(HingeExact, LimitWithSmallerCostWinsNotTheNearerAngle) {
  SimpleHinge h(0, kPi / 2);
  // 170 deg: the upper limit is both nearer and cheaper.
  JointSolveResult r = h.exact(170, 10);
  EXPECT_EQ(r.value, kPi / 2);
  EXPECT_EQ(r.termination, JointTermination::AtLimit);
  // -100 deg seen from previous = 85 deg: the nearest turn is 260 deg, a naive clamp of it gives 90 deg,
  // but the pose at 0 is 100 deg away from the target and the one at 90 deg is 170 deg away.
  r = h.exact(-100, 85);
  EXPECT_EQ(r.value, 0.0);
  EXPECT_EQ(r.termination, JointTermination::AtLimit);
  r = h.exact(-120, 80);  // nearest turn 240 deg, clamp -> 90 deg (150 away); 0 is 120 away
  EXPECT_EQ(r.value, 0.0);
  EXPECT_LT(r.cost, pose_cost(h.verts.points, h.target(-120), h.target(90)));
}

TEST(HingeExact, LimitedResultIsTheGlobalConstrainedMinimum) {
  Rng rng(11);
  for (int trial = 0; trial < 200; ++trial) {
    double lo = rng.uniform(-4, 4), hi = lo + rng.uniform(0, 2 * kPi);
    SimpleHinge h(lo, hi);
    double target = rng.uniform(-360, 360), prev = rng.uniform(lo, hi) / kDeg;
    JointSolveResult r = h.exact(target, prev);
    ASSERT_GE(r.value, lo);
    ASSERT_LE(r.value, hi);
    double best = INFINITY;  // dense scan of the cost over [lo, hi], straight from the vertices
    for (int i = 0; i <= 2000; ++i) {
      double th = lo + (hi - lo) * i / 2000;
      best = std::min(best, pose_cost(h.verts.points, h.target(target), hinge_child_pose(h.frame, h.parent, th)));
    }
    EXPECT_LE(r.cost, best + 1e-12) << "lo " << lo << " hi " << hi << " target " << target;
  }
}


TEST(HingeExact, DegenerateInputKeepsPreviousAngle) {
  HingeDef d;
  d.parent = {1, 1};
  d.child = {2, 1};
  d.axis_parent = Vec3(0, 1, 0);
  d.axis_child = Vec3(0, 0, 1);
  d.pivot_child = Vec3(0.1, 0.2, 0.3);
  d.lower = -1;
  d.upper = 1;
  HingeFrame f = make_hinge_frame(d);
  Rng rng(3);
  for (double radius : {0.0, 1e-6}) {  // on the axis, and within 1 um of it
    Eigen::Matrix3Xd p(3, 50);
    for (int k = 0; k < 50; ++k) {
      Vec3 off = rng.unit().cross(d.axis_child);
      p.col(k) = d.pivot_child + rng.uniform(-0.2, 0.2) * d.axis_child +
                 (off.norm() > 0 ? Vec3(radius * off.normalized()) : Vec3::Zero());
    }
    JointVertices v = make_joint_vertices(p, {}, d.pivot_child);
    Pose parent = rng.pose(1), sim = rng.pose(1);
    for (JointSolver s : {JointSolver::Exact, JointSolver::Lm
#if HANDSIM_WITH_CERES
                          , JointSolver::LmCeres
#endif
         }) {
      JointSolveResult r = solve_hinge(s, f, v, parent, sim, 0.25);
      EXPECT_EQ(r.value, 0.25) << "solver " << int(s) << " radius " << radius;
      EXPECT_EQ(r.termination, JointTermination::Degenerate);
      EXPECT_TRUE(std::isfinite(r.cost));
    }
  }
}

TEST(HingeExact, FlatCostKeepsPreviousAngle) {
  // Vertices symmetric about the pivot, target = the rest pose turned 180 deg about an axis normal to the
  // hinge: every theta gives the same cost (a = b = 0).
  SimpleHinge h;
  Eigen::Matrix3Xd p(3, 2);
  p << 0, 0, 0.1, -0.1, 0, 0;
  JointVertices v = make_joint_vertices(p, {}, Vec3::Zero());
  // Turned -90 deg about Z: both vertices land on the hinge axis, so q_perp = 0 for every vertex.
  Pose flipped{Vec3::Zero(), Quat(Eigen::AngleAxisd(-kPi / 2, Vec3::UnitZ()))};
  JointSolveResult r = solve_hinge_exact(h.frame, v.moments, h.parent, flipped, 0.7);
  EXPECT_EQ(r.termination, JointTermination::Degenerate);
  EXPECT_EQ(r.value, 0.7);
}

TEST(HingeExact, FarFromTheOriginKeepsNanoradians) {
  Rng rng(5);
  double worst_scene = 0, worst_authored = 0;
  for (int trial = 0; trial < 20; ++trial) {
    // (a) the whole scene 10 km out: body frames at 10 km, geometry local.
    HingeCase a = random_hinge(rng, 64, 0.005, 0.05);
    Vec3 far(1e4, 2e3, -1e4);
    a.parent.position += far;
    a.sim.position += far;
    LD ref_a = reference_of(a);
    worst_scene = std::max(worst_scene, std::abs(wrap(
        solve_hinge_exact(a.frame, a.verts.moments, a.parent, a.sim, double(ref_a)).value - double(ref_a))));
    // (b) meshes authored in world coordinates: body frames at the origin, pivot and vertices at 10 km.
    HingeCase b = random_hinge(rng, 64, 0.005, 0.05, Vec3(1e4, -3e3, 1e4));
    LD ref_b = reference_of(b);
    worst_authored = std::max(worst_authored, std::abs(wrap(
        solve_hinge_exact(b.frame, b.verts.moments, b.parent, b.sim, double(ref_b)).value - double(ref_b))));
  }
  EXPECT_LE(worst_scene, 1e-9);
  EXPECT_LE(worst_authored, 1e-9);
}

TEST(HingeExact, RejectsMomentsAboutAnotherPoint) {
  SimpleHinge h;
  VertexMoments m = vertex_moments(h.verts.points, {}, Vec3(0, 0, 0.1));
  try {
    solve_hinge_exact(h.frame, m, h.parent, h.target(10), 0);
    FAIL();
  } catch (const Error& e) {
    EXPECT_EQ(e.argument(), "moments");
  }
}

// ---------------------------------------------------------------------------------------------- hinge LM

std::vector<JointSolver> lm_solvers() {
#if HANDSIM_WITH_CERES
  return {JointSolver::Lm, JointSolver::LmCeres};
#else
  return {JointSolver::Lm};
#endif
}

TEST(HingeLm, ConvergesToExactFromSmallAndLargePerturbations) {
  // Zero residual: Gauss-Newton converges quadratically, to the last bit, well within 10 iterations.
  Rng rng(21);
  for (JointSolver s : lm_solvers()) {
    for (double start_off : {0.05, -0.5, 1.5, -2.5}) {
      for (int trial = 0; trial < 10; ++trial) {
        HingeCase c = random_hinge(rng, 64, 0, 0);
        JointSolveResult lm = solve_hinge(s, c.frame, c.verts, c.parent, c.sim, c.theta_true + start_off);
        EXPECT_NEAR(lm.value, c.theta_true, 1e-12) << "solver " << int(s) << " start offset " << start_off;
        EXPECT_EQ(lm.termination, JointTermination::Converged);
        EXPECT_LE(lm.iterations, 10);
      }
    }
  }
}

TEST(HingeLm, NoisyTargetsReachTheRoundingFloorOfTheCost) {
  // Documented: with a residual (2 mm, 0.02 rad of hand noise on a 0.1 m body) convergence is linear and
  // both LM modes stop on cost-based tests, whose floor is ~sqrt(eps) * rms residual / rms lever in theta
  // (measured worst ~2e-9 rad). The exact solver has no such floor.
  Rng rng(22);
  for (JointSolver s : lm_solvers()) {
    for (double start_off : {0.05, -0.5, 1.5, -2.5}) {
      for (int trial = 0; trial < 10; ++trial) {
        HingeCase c = random_hinge(rng, 64, 0.002, 0.02);
        JointSolveResult ex = solve_hinge_exact(c.frame, c.verts.moments, c.parent, c.sim, c.theta_true);
        JointSolveResult lm = solve_hinge(s, c.frame, c.verts, c.parent, c.sim, ex.value + start_off);
        EXPECT_NEAR(lm.value, ex.value, 1e-8) << "solver " << int(s) << " start offset " << start_off;
        EXPECT_LE(lm.iterations, 10);
        EXPECT_NEAR(lm.cost, ex.cost, 1e-9 * ex.cost);
      }
    }
  }
}

TEST(HingeLm, StartOnTheCostMaximumStaysThere) {
  // Documented: a local method stops at the stationary point it starts on.
  SimpleHinge h;
  for (JointSolver s : lm_solvers()) {
    JointSolveResult r = solve_hinge(s, h.frame, h.verts, h.parent, h.target(40), (40 + 180) * kDeg);
    EXPECT_NEAR(r.value, 220 * kDeg, 1e-9) << int(s);
    EXPECT_GT(r.cost, 0.01);  // the worst pose, far from zero
  }
}

TEST(HingeLm, NearTheMaximumTenIterationsAreNotEnough) {
  // Documented: near the maximum a Gauss-Newton step roughly doubles the distance from it, so from
  // 1e-4 rad off the maximum ten iterations end far from the optimum.
  SimpleHinge h;
  for (JointSolver s : lm_solvers()) {
    JointSolveResult r = solve_hinge(s, h.frame, h.verts, h.parent, h.target(40), (220 - 1e-4 / kDeg) * kDeg);
    EXPECT_EQ(r.termination, JointTermination::MaxIterations) << int(s);
    EXPECT_GT(std::abs(wrap(r.value - 40 * kDeg)), 0.1) << int(s);
    JointSolveOptions more;
    more.max_iterations = 100;
    r = solve_hinge(s, h.frame, h.verts, h.parent, h.target(40), (220 - 1e-4 / kDeg) * kDeg, more);
    EXPECT_NEAR(wrap(r.value - 40 * kDeg), 0, 1e-9) << int(s);
  }
}

TEST(HingeLm, LimitsAreEnforcedButTheLimitFoundIsLocal) {
  SimpleHinge h(0, kPi / 2);
  for (JointSolver s : lm_solvers()) {
    // Beyond the upper limit, descending towards it: stops on it.
    JointSolveResult r = solve_hinge(s, h.frame, h.verts, h.parent, h.target(120), 60 * kDeg);
    EXPECT_NEAR(r.value, kPi / 2, 1e-12) << int(s);
    EXPECT_EQ(r.termination, JointTermination::AtLimit) << int(s);
    // Target -120 deg from 80 deg: descent goes up to 90 deg, a local minimum on the box, while the exact
    // solver returns the cheaper lower limit. Documented behaviour of the LM modes.
    r = solve_hinge(s, h.frame, h.verts, h.parent, h.target(-120), 80 * kDeg);
    EXPECT_NEAR(r.value, kPi / 2, 1e-12) << int(s);
    EXPECT_EQ(h.exact(-120, 80).value, 0.0);
  }
}

#if !HANDSIM_WITH_CERES
TEST(HingeLm, CeresModeWithoutCeresIsUnsupported) {
  SimpleHinge h;
  try {
    solve_hinge(JointSolver::LmCeres, h.frame, h.verts, h.parent, h.target(10), 0);
    FAIL();
  } catch (const Error& e) {
    EXPECT_EQ(e.status(), Status::Unsupported);
    EXPECT_EQ(e.argument(), "solver");
  }
}
#endif

// -------------------------------------------------------------------------------------- pose helpers

TEST(HingePose, AngleRoundTripAndViolation) {
  Rng rng(31);
  HingeCase c = random_hinge(rng, 8, 0, 0);
  for (double th : {-3.0, -0.5, 0.0, 1.0, 3.1, 10.0}) {
    Pose child = hinge_child_pose(c.frame, c.parent, th);
    EXPECT_NEAR(hinge_angle(c.frame, c.parent, child, th), th, 1e-12);
    EXPECT_LE(hinge_violation(c.frame, c.parent, child, 0.1), 1e-12);
  }
  Pose child = hinge_child_pose(c.frame, c.parent, 0.3);
  child.position += Vec3(0.001, 0, 0);
  EXPECT_NEAR(hinge_violation(c.frame, c.parent, child, 0.1), 0.001, 1e-12);
  // Tilting the child about the pivot by 0.01 rad across the axis: 0.01 * length.
  child = hinge_child_pose(c.frame, c.parent, 0.3);
  Vec3 pivot = child.transform(c.frame.pivot_child);
  Vec3 across = (c.parent.orientation * c.frame.axis_parent).unitOrthogonal();
  Quat tilt(Eigen::AngleAxisd(0.01, across));
  Pose tilted{tilt * (child.position - pivot) + pivot, tilt * child.orientation};
  EXPECT_NEAR(hinge_violation(c.frame, c.parent, tilted, 0.1), 0.001, 1e-9);
}

TEST(HingePose, WorldParentAndAuthoringFromWorld) {
  Pose parent{Vec3(1, 2, 3), Quat(Eigen::AngleAxisd(0.4, Vec3::UnitY()))};
  Pose child{Vec3(1.5, 2, 3), Quat(Eigen::AngleAxisd(-0.3, Vec3::UnitZ()))};
  HingeDef d = hinge_from_world({1, 1}, parent, {2, 1}, child, Vec3(1.2, 2, 3), Vec3(0, 0, 1));
  HingeFrame f = make_hinge_frame(d);
  EXPECT_NEAR(hinge_angle(f, parent, child), 0.0, 1e-12);
  EXPECT_LE(hinge_violation(f, parent, child, 1.0), 1e-12);
  Pose turned = hinge_child_pose(f, parent, 0.5);
  EXPECT_NEAR((turned.transform(d.pivot_child) - Vec3(1.2, 2, 3)).norm(), 0, 1e-12);
}

// ------------------------------------------------------------------------------------------------ slider

struct SliderCase {
  SliderFrame frame;
  JointVertices verts;
  Pose parent, sim;
};

SliderCase random_slider(Rng& rng, double lower, double upper, double s_true, const Vec3& offset = Vec3::Zero()) {
  SliderDef d;
  d.parent = {1, 1};
  d.child = {2, 1};
  d.anchor_parent = offset + rng.vec(0.2);
  d.anchor_child = offset + rng.vec(0.2);
  d.axis = rng.unit();
  d.rest_orientation = rng.quat();
  d.lower = lower;
  d.upper = upper;
  SliderCase c;
  c.frame = make_slider_frame(d);
  c.verts = make_joint_vertices(rng.points(64, d.anchor_child + rng.vec(0.1), 0.1), {}, d.anchor_child);
  c.parent = rng.pose(1);
  Pose exact = slider_child_pose(c.frame, c.parent, s_true);
  Pose m = small_motion(rng, 0.01, 0.1);
  c.sim = {exact.position + m.position, (m.orientation * exact.orientation).normalized()};
  return c;
}

// Long double: the weighted mean of the per-vertex displacement along the axis.
LD slider_reference(const SliderCase& c) {
  PairsL p = pairs_ld(c.frame.anchor_parent, c.frame.anchor_child, c.frame.rest, c.verts.points, c.parent, c.sim);
  LD sum = 0;
  for (size_t k = 0; k < p.q.size(); ++k) sum += c.frame.axis.cast<LD>().dot(p.q[k] - p.u[k]);
  return sum / p.q.size();
}

TEST(Slider, ExactMatchesReferenceAndLmModesAgree) {
  Rng rng(41);
  for (int trial = 0; trial < 30; ++trial) {
    SliderCase c = random_slider(rng, -kUnlimited, kUnlimited, rng.uniform(-1, 1));
    LD ref = slider_reference(c);
    JointSolveResult ex = solve_slider_exact(c.frame, c.verts.moments, c.parent, c.sim, 0);
    EXPECT_NEAR(ex.value, double(ref), 1e-13);
    EXPECT_EQ(ex.termination, JointTermination::Converged);
    EXPECT_NEAR(ex.cost, pose_cost(c.verts.points, c.sim, slider_child_pose(c.frame, c.parent, ex.value)),
                1e-12 * ex.cost);
    for (JointSolver s : lm_solvers()) {
      JointSolveResult lm = solve_slider(s, c.frame, c.verts, c.parent, c.sim, 3.0);
      EXPECT_NEAR(lm.value, ex.value, 1e-12) << int(s);
      // A quadratic: the Eigen LM's damped steps shrink the error ~1e4x each. Ceres, with our tight
      // tolerances, also solves it in one step but may spend more iterations on rounding-level trials.
      EXPECT_LE(lm.iterations, s == JointSolver::Lm ? 5 : 10) << int(s);
    }
  }
}

TEST(Slider, ClampsToTheLimitAndIsExactFarOut) {
  Rng rng(43);
  SliderCase c = random_slider(rng, -0.1, 0.2, 0.5);
  for (JointSolver s : {JointSolver::Exact, JointSolver::Lm}) {
    JointSolveResult r = solve_slider(s, c.frame, c.verts, c.parent, c.sim, 0);
    EXPECT_EQ(r.value, 0.2) << int(s);
    EXPECT_EQ(r.termination, JointTermination::AtLimit) << int(s);
  }
  SliderCase f = random_slider(rng, -kUnlimited, kUnlimited, 0.3, Vec3(1e4, 1e4, -1e4));
  EXPECT_NEAR(solve_slider_exact(f.frame, f.verts.moments, f.parent, f.sim, 0).value, double(slider_reference(f)),
              1e-9);
  Pose child = slider_child_pose(f.frame, f.parent, 0.3);
  EXPECT_NEAR(slider_displacement(f.frame, f.parent, child), 0.3, 1e-9);
  EXPECT_LE(slider_violation(f.frame, f.parent, child, 0.1), 1e-9);
}

// -------------------------------------------------------------------------------------------------- ball

struct BallCase {
  BallFrame frame;
  JointVertices verts;
  Pose parent;
};

BallCase make_ball(Rng& rng, const Eigen::Matrix3Xd& local_pts, std::optional<double> cone = std::nullopt) {
  BallDef d;
  d.parent = {1, 1};
  d.child = {2, 1};
  d.pivot_parent = rng.vec(0.2);
  d.pivot_child = rng.vec(0.2);
  d.rest_orientation = rng.quat();
  d.cone_axis = Vec3::UnitY();
  d.cone_half_angle = cone;
  BallCase c;
  c.frame = make_ball_frame(d);
  Eigen::Matrix3Xd pts = local_pts.colwise() + d.pivot_child;
  c.verts = make_joint_vertices(pts, {}, d.pivot_child);
  c.parent = rng.pose(1);
  return c;
}

double ball_cost(const BallCase& c, const Pose& sim, const Quat& r) {
  return pose_cost(c.verts.points, sim, ball_child_pose(c.frame, c.parent, r));
}

TEST(Ball, RecoversRotationAndIsALocalMinimumUnderNoise) {
  Rng rng(51);
  for (int trial = 0; trial < 30; ++trial) {
    BallCase c = make_ball(rng, rng.points(64, rng.vec(0.1), 0.1));
    Quat truth = rng.quat();
    Pose sim = ball_child_pose(c.frame, c.parent, truth);
    BallSolveResult r = solve_ball_exact(c.frame, c.verts.moments, c.parent, sim, Quat::Identity());
    EXPECT_LE(r.rotation.angularDistance(truth), 1e-12);
    EXPECT_EQ(r.termination, JointTermination::Converged);
    Pose m = small_motion(rng, 0.01, 0.1);
    Pose noisy{sim.position + m.position, (m.orientation * sim.orientation).normalized()};
    r = solve_ball_exact(c.frame, c.verts.moments, c.parent, noisy, Quat::Identity());
    double c0 = ball_cost(c, noisy, r.rotation);
    EXPECT_NEAR(r.cost, c0, 1e-12 * c0);
    for (int i = 0; i < 20; ++i) {  // optimality: every small rotation away costs more
      Quat nudged = (Quat(Eigen::AngleAxisd(1e-4, rng.unit())) * r.rotation).normalized();
      EXPECT_GE(ball_cost(c, noisy, nudged), c0);
    }
  }
}

TEST(Ball, PlanarVerticesNeedTheReflectionFix) {
  // Three coplanar vertices through the pivot's plane: H has a zero singular value, and U V^T can be a
  // reflection; the fix must still return the proper rotation.
  Rng rng(53);
  Eigen::Matrix3Xd p(3, 3);
  p << 0.1, 0, -0.1, 0, 0.1, 0.05, 0, 0, 0;
  for (int trial = 0; trial < 30; ++trial) {
    BallCase c = make_ball(rng, p);
    Quat truth = rng.quat();
    BallSolveResult r = solve_ball_exact(c.frame, c.verts.moments, c.parent,
                                         ball_child_pose(c.frame, c.parent, truth), Quat::Identity());
    EXPECT_NEAR(r.rotation.toRotationMatrix().determinant(), 1.0, 1e-12);
    EXPECT_LE(r.rotation.angularDistance(truth), 1e-10);
  }
}

TEST(Ball, DegenerateRodAndPoint) {
  Rng rng(55);
  Eigen::Matrix3Xd rod(3, 5);
  rod << 0, 0, 0, 0, 0, -0.2, -0.1, 0.05, 0.1, 0.2, 0, 0, 0, 0, 0;
  BallCase c = make_ball(rng, rod);
  Quat truth = rng.quat(), prev = rng.quat();
  BallSolveResult r = solve_ball_exact(c.frame, c.verts.moments, c.parent,
                                       ball_child_pose(c.frame, c.parent, truth), prev);
  EXPECT_EQ(r.termination, JointTermination::Degenerate);
  EXPECT_LE(r.cost, 1e-20);  // the rod lands on its target; only its own twist is unobserved
  Eigen::Matrix3Xd dot = Eigen::Matrix3Xd::Zero(3, 3);
  BallCase d = make_ball(rng, dot);
  r = solve_ball_exact(d.frame, d.verts.moments, d.parent, rng.pose(1), prev);
  EXPECT_EQ(r.termination, JointTermination::Degenerate);
  EXPECT_LE(r.rotation.angularDistance(prev), 1e-15);
}

TEST(Ball, ConeLimitProjectsTheSwingAndReoptimizesTwist) {
  Rng rng(57);
  for (int trial = 0; trial < 20; ++trial) {
    BallCase c = make_ball(rng, rng.points(32, rng.vec(0.1), 0.1), 0.5);
    Quat truth = rng.quat();
    Pose sim = ball_child_pose(c.frame, c.parent, truth);
    BallSolveResult r = solve_ball_exact(c.frame, c.verts.moments, c.parent, sim, Quat::Identity());
    Vec3 n = c.frame.cone_axis, m = r.rotation * n;
    double swing = std::atan2(n.cross(m).norm(), n.dot(m));
    Vec3 mt = truth * n;
    double swing_true = std::atan2(n.cross(mt).norm(), n.dot(mt));
    if (swing_true <= 0.5) {
      EXPECT_LE(r.rotation.angularDistance(truth), 1e-10);
      continue;
    }
    EXPECT_EQ(r.termination, JointTermination::AtLimit);
    EXPECT_NEAR(swing, 0.5, 1e-12);
    // The swing direction stays on the great circle from n towards the unconstrained direction.
    EXPECT_NEAR(n.cross(m).normalized().dot(n.cross(mt).normalized()), 1.0, 1e-9);
    // The twist is optimal for that swing: turning about n at the clamped swing costs more both ways.
    for (double eps : {1e-4, -1e-4}) {
      Quat twisted = (r.rotation * Quat(Eigen::AngleAxisd(eps, n))).normalized();
      EXPECT_GE(ball_cost(c, sim, twisted), r.cost);
    }
  }
}

TEST(Ball, PoseHelpers) {
  Rng rng(59);
  BallCase c = make_ball(rng, rng.points(8, Vec3::Zero(), 0.1));
  Quat q = rng.quat();
  Pose child = ball_child_pose(c.frame, c.parent, q);
  EXPECT_LE(ball_rotation(c.frame, c.parent, child).angularDistance(q), 1e-12);
  EXPECT_LE(ball_violation(c.frame, c.parent, child), 1e-12);
}

// ------------------------------------------------------------------------------------------------- fixed

TEST(Fixed, ChildPoseAndViolation) {
  Rng rng(61);
  FixedDef d;
  d.parent = {1, 1};
  d.child = {2, 1};
  d.relative = rng.pose(0.5);
  FixedFrame f = make_fixed_frame(d);
  Pose parent = rng.pose(1);
  Pose child = fixed_child_pose(f, parent);
  EXPECT_LE(fixed_violation(f, parent, child, 0.1), 1e-12);
  EXPECT_LE((parent.inverse() * child).position.isApprox(d.relative.position, 1e-12) ? 0 : 1, 0);
  child.position.y() += 0.002;
  EXPECT_NEAR(fixed_violation(f, parent, child, 0.1), 0.002, 1e-12);
}

// -------------------------------------------------------------------------------------------- validation

template <class Def>
void expect_error(const Def& def, const std::string& field) {
  try {
    validate_joint(def, "joint");
    ADD_FAILURE() << "no error for " << field;
  } catch (const Error& e) {
    EXPECT_EQ(e.argument(), "joint." + field);
    EXPECT_EQ(std::string(e.what()).rfind("joint." + field, 0), 0u);
  }
}

HingeDef good_hinge() {
  HingeDef d;
  d.parent = {1, 1};
  d.child = {2, 1};
  d.lower = -1;
  d.upper = 1;
  return d;
}

TEST(Validation, BadHingeNamesTheField) {
  EXPECT_NO_THROW(validate_joint(good_hinge(), "joint"));
  HingeDef world_parent = good_hinge();
  world_parent.parent = {};
  EXPECT_NO_THROW(validate_joint(world_parent, "joint"));
  const double nan = std::nan("");
  auto with = [](auto edit) {
    HingeDef d = good_hinge();
    edit(d);
    return d;
  };
  expect_error(with([](HingeDef& d) { d.axis_parent = Vec3::Zero(); }), "axis_parent");
  expect_error(with([&](HingeDef& d) { d.axis_child = Vec3(nan, 0, 1); }), "axis_child");
  expect_error(with([&](HingeDef& d) { d.pivot_parent.x() = nan; }), "pivot_parent");
  expect_error(with([&](HingeDef& d) { d.pivot_child.z() = INFINITY; }), "pivot_child");
  expect_error(with([](HingeDef& d) { d.lower = 2; }), "lower");
  expect_error(with([&](HingeDef& d) { d.lower = nan; }), "lower");
  expect_error(with([&](HingeDef& d) { d.upper = nan; }), "upper");
  expect_error(with([](HingeDef& d) { d.upper = 1e308; }), "upper");  // beyond +-1e6 rad
  expect_error(with([](HingeDef& d) { d.lower = -1e7; }), "lower");
  expect_error(with([](HingeDef& d) { d.pivot_child = Vec3(1e308, 0, 0); }), "pivot_child");  // was NaN
  EXPECT_NO_THROW(validate_joint(with([](HingeDef& d) { d.lower = -4, d.upper = 3; }), "joint"));  // > 2 pi
  EXPECT_NO_THROW(validate_joint(with([](HingeDef& d) { d.axis_parent = Vec3(1e308, 0, 0); }), "joint"));
  expect_error(with([](HingeDef& d) { d.child = d.parent; }), "child");
  expect_error(with([](HingeDef& d) { d.child = {}; }), "child");
  expect_error(with([](HingeDef& d) { d.damping = -0.1; }), "damping");
  expect_error(with([](HingeDef& d) { d.solver = JointSolver(7); }), "solver");
  expect_error(with([](HingeDef& d) { d.model = JointModel(7); }), "model");
  expect_error(with([](HingeDef& d) { d.rest_orientation = Quat(Eigen::AngleAxisd(0.3, Vec3::UnitY())); }),
               "rest_orientation");
  EXPECT_NO_THROW(validate_joint(with([](HingeDef& d) { d.lower = -kPi, d.upper = kPi; }), "joint"));
  EXPECT_NO_THROW(validate_joint(with([](HingeDef& d) { d.lower = -kUnlimited, d.upper = 5; }), "joint"));
}

TEST(Validation, BadSliderBallFixedNameTheField) {
  SliderDef s;
  s.parent = {1, 1};
  s.child = {2, 1};
  EXPECT_NO_THROW(validate_joint(s, "joint"));
  SliderDef s1 = s;
  s1.axis = Vec3::Zero();
  expect_error(s1, "axis");
  SliderDef s2 = s;
  s2.lower = 1, s2.upper = 0;
  expect_error(s2, "lower");
  SliderDef s3 = s;
  s3.rest_orientation = Quat(0, 0, 0, 2);
  expect_error(s3, "rest_orientation");

  BallDef b;
  b.parent = {1, 1};
  b.child = {2, 1};
  EXPECT_NO_THROW(validate_joint(b, "joint"));
  BallDef b1 = b;
  b1.cone_half_angle = 4.0;
  expect_error(b1, "cone_half_angle");
  BallDef b2 = b;
  b2.cone_half_angle = 0.5;
  b2.cone_axis = Vec3::Zero();
  expect_error(b2, "cone_axis");
  BallDef b3 = b;
  b3.solver = JointSolver::Lm;
  expect_error(b3, "solver");
  BallDef b4 = b;
  b4.damping = std::nan("");
  expect_error(b4, "damping");

  FixedDef f;
  f.parent = {1, 1};
  f.child = {2, 1};
  EXPECT_NO_THROW(validate_joint(f, "joint"));
  f.relative.position.x() = std::nan("");
  expect_error(f, "relative.position");
}

TEST(Validation, BadVertices) {
  Eigen::Matrix3Xd none(3, 0);
  EXPECT_THROW(vertex_moments(none, {}, Vec3::Zero()), Error);
  Eigen::Matrix3Xd two = Eigen::Matrix3Xd::Ones(3, 2);
  Eigen::VectorXd bad(2);
  bad << 1, -1;
  try {
    vertex_moments(two, bad, Vec3::Zero());
    FAIL();
  } catch (const Error& e) {
    EXPECT_EQ(e.argument(), "weights");
  }
}

}  // namespace
}  // namespace handsim
