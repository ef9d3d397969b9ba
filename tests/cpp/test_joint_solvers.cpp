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

}  // namespace
}  // namespace handsim
