#include "pose_fit.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <random>

using namespace handsim;

namespace {

struct Rng {
  std::mt19937_64 gen{12345};
  double uniform(double a, double b) { return std::uniform_real_distribution<double>(a, b)(gen); }
  Vec3 vec(double r) { return Vec3(uniform(-r, r), uniform(-r, r), uniform(-r, r)); }
  Quat rotation() {
    Quat q(uniform(-1, 1), uniform(-1, 1), uniform(-1, 1), uniform(-1, 1));
    return q.normalized();
  }
};

std::vector<Vec3> transformed(const std::vector<Vec3>& x, const Mat3& R, const Vec3& t) {
  std::vector<Vec3> y;
  for (const Vec3& xi : x) y.push_back(R * xi + t);
  return y;
}

double cost(const std::vector<Vec3>& q, const std::vector<Vec3>& p, const std::vector<double>& w,
            const Mat3& R, const Vec3& t) {
  double c = 0;
  for (size_t i = 0; i < q.size(); ++i) c += w[i] * (R * q[i] + t - p[i]).squaredNorm();
  return c;
}

bool finite(const RigidMotion& m) {
  return m.R.allFinite() && m.t.allFinite() && m.pivot.allFinite() && m.shift.allFinite();
}

Vec3 weighted_centroid(const std::vector<Vec3>& x, const std::vector<double>& w) {
  Vec3 c = Vec3::Zero();
  double W = 0;
  for (size_t i = 0; i < x.size(); ++i) c += w[i] * x[i], W += w[i];
  return c / W;
}

// Minimal-norm line case: R maps the direction of `dq` onto that of `dp` by the shortest arc (its axis is
// perpendicular to both, so there is no twist about the line), and the weighted centroid of q lands on p's.
void expect_line_motion(const RigidMotion& m, const Vec3& dq, const Vec3& dp, const Vec3& cq, const Vec3& cp) {
  EXPECT_EQ(m.constrained_dofs, 5);
  EXPECT_LE((m.R * dq.normalized() - dp.normalized()).norm(), 1e-12);
  Vec3 rv = rotation_vector(m.R);
  double angle = std::acos(std::clamp(dq.normalized().dot(dp.normalized()), -1.0, 1.0));
  EXPECT_NEAR(rv.norm(), angle, 1e-12);
  EXPECT_LE(std::abs(rv.dot(dq.normalized())), 1e-12);  // no twist: the axis is perpendicular to the line
  EXPECT_LE((m.apply(cq) - cp).norm(), 1e-12);
  EXPECT_LE((m.R * cq + m.t - cp).norm(), 1e-12);
  EXPECT_NEAR(m.R.determinant(), 1.0, 1e-12);
}

}  // namespace

TEST(PoseFit, RecoversRandomRigidMotionWithWeights) {
  Rng rng;
  for (int trial = 0; trial < 50; ++trial) {
    int n = 3 + trial % 20;
    std::vector<Vec3> q;
    std::vector<double> w;
    for (int i = 0; i < n; ++i) q.push_back(rng.vec(0.1)), w.push_back(rng.uniform(0.01, 2.0));
    Mat3 R = rng.rotation().toRotationMatrix();
    Vec3 t = rng.vec(0.5);
    RigidMotion m = fit_rigid_motion(q, transformed(q, R, t), w);
    EXPECT_EQ(m.constrained_dofs, 6);
    EXPECT_LE((m.R - R).norm(), 1e-12) << "trial " << trial;
    EXPECT_LE((m.t - t).norm(), 1e-12) << "trial " << trial;
    EXPECT_NEAR(m.R.determinant(), 1.0, 1e-12);
    EXPECT_LE((m.pivot - weighted_centroid(q, w)).norm(), 1e-14);
    for (const Vec3& qi : q) EXPECT_LE((m.apply(qi) - (R * qi + t)).norm(), 1e-12);
  }
}

TEST(PoseFit, ZeroWeightPointsAreIgnored) {
  Rng rng;
  std::vector<Vec3> q{rng.vec(0.1), rng.vec(0.1), rng.vec(0.1), rng.vec(0.1)};
  Mat3 R = rng.rotation().toRotationMatrix();
  Vec3 t = rng.vec(0.5);
  std::vector<Vec3> p = transformed(q, R, t);
  p.push_back(Vec3(5, 5, 5));  // an outlier with no weight
  q.push_back(Vec3(-5, 0, 0));
  RigidMotion m = fit_rigid_motion(q, p, {1, 2, 3, 4, 0});
  EXPECT_LE((m.R - R).norm(), 1e-12);
  EXPECT_LE((m.t - t).norm(), 1e-12);
}

TEST(PoseFit, CoplanarPointsRecoverRotationNotReflection) {
  // With exactly coplanar points the third singular value is 0 and a naive V U^T has an arbitrary sign.
  Rng rng;
  std::vector<Vec3> q{{0, 0, 0}, {0.1, 0, 0}, {0, 0.1, 0}, {0.07, 0.05, 0}};
  for (int trial = 0; trial < 20; ++trial) {
    Mat3 R = rng.rotation().toRotationMatrix();
    Vec3 t = rng.vec(1.0);
    RigidMotion m = fit_rigid_motion(q, transformed(q, R, t));
    EXPECT_EQ(m.constrained_dofs, 6);
    EXPECT_LE((m.R - R).norm(), 1e-12);
    EXPECT_LE((m.t - t).norm(), 1e-12);
  }
}

TEST(PoseFit, MirroredTargetGivesProperRotation) {
  // p is the mirror image of q through the plane z = 0: the naive Kabsch answer is that mirror.
  std::vector<Vec3> q{{0.1, 0, 0.05}, {-0.05, 0.08, 0.02}, {-0.05, -0.08, -0.04}, {0.02, 0.01, -0.09}};
  Mat3 mirror = Vec3(1, 1, -1).asDiagonal();
  std::vector<Vec3> p = transformed(q, mirror, Vec3::Zero());

  Mat3 H = Mat3::Zero();
  Vec3 cq = weighted_centroid(q, {1, 1, 1, 1}), cp = weighted_centroid(p, {1, 1, 1, 1});
  for (size_t i = 0; i < q.size(); ++i) H += (q[i] - cq) * (p[i] - cp).transpose();
  Eigen::JacobiSVD<Mat3> svd(H, Eigen::ComputeFullU | Eigen::ComputeFullV);
  Mat3 naive = svd.matrixV() * svd.matrixU().transpose();
  ASSERT_LT(naive.determinant(), 0) << "the test data must be a case the naive SVD mirrors";

  RigidMotion m = fit_rigid_motion(q, p);
  EXPECT_NEAR(m.R.determinant(), 1.0, 1e-12);
  EXPECT_LE((m.R * m.R.transpose() - Mat3::Identity()).norm(), 1e-12);
  EXPECT_TRUE(finite(m));
  // It is the best proper rotation: no small rotation about it does better.
  std::vector<double> w(q.size(), 1.0);
  double best = cost(q, p, w, m.R, m.t);
  for (int axis = 0; axis < 3; ++axis)
    for (double a : {-1e-3, 1e-3}) {
      Mat3 dR = Eigen::AngleAxisd(a, Vec3::Unit(axis)).toRotationMatrix();
      Mat3 R2 = dR * m.R;
      Vec3 t2 = cp - R2 * cq;
      EXPECT_GE(cost(q, p, w, R2, t2), best);
    }
}

TEST(PoseFit, NoContactsOrNoWeightIsIdentity) {
  RigidMotion none = fit_rigid_motion({}, {});
  EXPECT_EQ(none.constrained_dofs, 0);
  EXPECT_EQ(none.R, Mat3::Identity());
  EXPECT_EQ(none.t, Vec3::Zero());

  RigidMotion unweighted = fit_rigid_motion({{1, 2, 3}, {0, 1, 0}}, {{2, 2, 2}, {5, 5, 5}}, {0.0, 0.0});
  EXPECT_EQ(unweighted.constrained_dofs, 0);
  EXPECT_EQ(unweighted.R, Mat3::Identity());
  EXPECT_EQ(unweighted.t, Vec3::Zero());
  EXPECT_EQ(unweighted.apply(Vec3(7, 8, 9)), Vec3(7, 8, 9));
}

TEST(PoseFit, OneContactIsPureTranslation) {
  Vec3 q(0.3, -0.2, 1.1), p(0.31, -0.19, 1.08);
  RigidMotion m = fit_rigid_motion({q}, {p}, {0.004});
  EXPECT_EQ(m.constrained_dofs, 3);
  EXPECT_EQ(m.R, Mat3::Identity());
  EXPECT_LE((m.t - (p - q)).norm(), 1e-15);
  EXPECT_TRUE(finite(m));
}

TEST(PoseFit, CoincidentContactsArePureTranslation) {
  Vec3 q(0.3, -0.2, 1.1);
  std::vector<Vec3> p{{0.31, -0.19, 1.08}, {0.29, -0.2, 1.1}, {0.3, -0.22, 1.12}};
  std::vector<double> w{1, 2, 3};
  RigidMotion m = fit_rigid_motion({q, q, q}, p, w);
  EXPECT_EQ(m.constrained_dofs, 3);
  EXPECT_EQ(m.R, Mat3::Identity());
  EXPECT_LE((m.t - (weighted_centroid(p, w) - q)).norm(), 1e-15);
}

TEST(PoseFit, TwoContactsGiveCentroidTranslationAndShortestArc) {
  Rng rng;
  for (int trial = 0; trial < 20; ++trial) {
    std::vector<Vec3> q{rng.vec(0.1), rng.vec(0.1)}, p{rng.vec(0.1), rng.vec(0.1)};
    std::vector<double> w{rng.uniform(0.1, 1), rng.uniform(0.1, 1)};
    RigidMotion m = fit_rigid_motion(q, p, w);
    expect_line_motion(m, q[1] - q[0], p[1] - p[0], weighted_centroid(q, w), weighted_centroid(p, w));
  }
}

TEST(PoseFit, CollinearContactsBehaveLikeTwo) {
  Rng rng;
  for (int n : {3, 5, 40}) {
    Vec3 a = rng.vec(0.2), dir = rng.vec(1).normalized();
    Mat3 R = rng.rotation().toRotationMatrix();
    Vec3 t = rng.vec(0.3);
    std::vector<Vec3> q;
    std::vector<double> w;
    for (int i = 0; i < n; ++i) q.push_back(a + rng.uniform(-0.1, 0.1) * dir), w.push_back(rng.uniform(0.1, 1));
    std::vector<Vec3> p = transformed(q, R, t);
    RigidMotion m = fit_rigid_motion(q, p, w);
    EXPECT_TRUE(finite(m));
    expect_line_motion(m, dir, R * dir, weighted_centroid(q, w), weighted_centroid(p, w));
    for (size_t i = 0; i < q.size(); ++i) EXPECT_LE((m.apply(q[i]) - p[i]).norm(), 1e-12);
  }
}

TEST(PoseFit, AntiparallelSegmentIsFinite) {
  // The shortest arc through 180 degrees is not unique; any half-turn about a perpendicular axis will do.
  std::vector<Vec3> q{{0, 0, 0}, {0.1, 0, 0}}, p{{0.1, 0, 0}, {0, 0, 0}};
  RigidMotion m = fit_rigid_motion(q, p);
  EXPECT_TRUE(finite(m));
  EXPECT_EQ(m.constrained_dofs, 5);
  EXPECT_LE((m.apply(q[0]) - p[0]).norm(), 1e-12);
  EXPECT_LE((m.apply(q[1]) - p[1]).norm(), 1e-12);
}

TEST(PoseFit, FarFromOriginKeepsDigits) {
  Rng rng;
  Vec3 far(1e4, -1e4, 1e4);
  for (int trial = 0; trial < 20; ++trial) {
    std::vector<Vec3> local;
    std::vector<double> w;
    for (int i = 0; i < 6; ++i) local.push_back(rng.vec(0.05)), w.push_back(rng.uniform(0.001, 0.01));
    // A small frame-to-frame motion about the far contacts' neighbourhood.
    Mat3 dR = Eigen::AngleAxisd(rng.uniform(0.001, 0.1), rng.vec(1).normalized()).toRotationMatrix();
    Vec3 dshift = rng.vec(0.01);
    std::vector<Vec3> q, p;
    for (const Vec3& l : local) q.push_back(far + l), p.push_back(far + dR * l + dshift);
    RigidMotion m = fit_rigid_motion(q, p, w);
    EXPECT_EQ(m.constrained_dofs, 6);
    EXPECT_LE((m.R - dR).norm(), 1e-9);
    for (size_t i = 0; i < q.size(); ++i) EXPECT_LE((m.apply(q[i]) - p[i]).norm(), 1e-9);
    // Two contacts far out still give the exact shortest-arc line motion.
    RigidMotion two = fit_rigid_motion({q[0], q[1]}, {p[0], p[1]});
    EXPECT_LE((two.R * (q[1] - q[0]).normalized() - (p[1] - p[0]).normalized()).norm(), 1e-9);
  }
}

TEST(PoseFit, NoisyDataIsLeastSquaresOptimal) {
  Rng rng;
  for (int trial = 0; trial < 10; ++trial) {
    std::vector<Vec3> q;
    std::vector<double> w;
    for (int i = 0; i < 12; ++i) q.push_back(rng.vec(0.1)), w.push_back(rng.uniform(0.1, 1));
    Mat3 R = rng.rotation().toRotationMatrix();
    std::vector<Vec3> p = transformed(q, R, rng.vec(0.2));
    for (Vec3& pi : p) pi += rng.vec(0.01);
    RigidMotion m = fit_rigid_motion(q, p, w);
    double best = cost(q, p, w, m.R, m.t);
    for (int k = 0; k < 200; ++k) {
      double scale = k < 100 ? 1e-3 : 1e-6;
      Mat3 dR = Eigen::AngleAxisd(rng.uniform(0, scale), rng.vec(1).normalized()).toRotationMatrix();
      EXPECT_GE(cost(q, p, w, dR * m.R, m.t + rng.vec(scale)), best - 1e-15);
      EXPECT_GE(cost(q, p, w, dR * m.R, m.t), best - 1e-15);
      EXPECT_GE(cost(q, p, w, m.R, m.t + rng.vec(scale)), best - 1e-15);
    }
  }
}

TEST(PoseFit, RejectsBadInput) {
  EXPECT_THROW(fit_rigid_motion({{0, 0, 0}}, {}), Error);
  EXPECT_THROW(fit_rigid_motion({{0, 0, 0}}, {{1, 0, 0}}, {1.0, 2.0}), Error);
  EXPECT_THROW(fit_rigid_motion({{0, 0, 0}}, {{1, 0, 0}}, {-1.0}), Error);
  EXPECT_THROW(fit_rigid_motion({{0, 0, NAN}}, {{1, 0, 0}}), Error);
  try {
    fit_rigid_motion({{0, 0, 0}, {1, 1, 1}}, {{1, 0, 0}, {0, INFINITY, 0}});
    FAIL();
  } catch (const Error& e) {
    EXPECT_EQ(e.argument(), "to[1]");
    EXPECT_EQ(e.status(), Status::InvalidArgument);
  }
}

TEST(PoseFit, ApplyMotionToPose) {
  Mat3 R = Eigen::AngleAxisd(0.5, Vec3::UnitY()).toRotationMatrix();
  RigidMotion m = RigidMotion::about(Vec3(1, 0, 0), R, Vec3(0, 0.1, 0));
  Pose pose{Vec3(2, 0, 0), Quat(Eigen::AngleAxisd(0.3, Vec3::UnitX()))};
  Pose moved = apply_motion(m, pose);
  EXPECT_LE((moved.position - (R * pose.position + m.t)).norm(), 1e-15);
  EXPECT_LE((moved.position - (Vec3(1, 0.1, 0) + R * Vec3(1, 0, 0))).norm(), 1e-15);
  EXPECT_LE((moved.orientation.toRotationMatrix() - R * pose.orientation.toRotationMatrix()).norm(), 1e-15);
  // A body point keeps its local coordinates: the motion moves the whole body rigidly.
  Vec3 local(0.1, 0.2, -0.3);
  EXPECT_LE((moved.transform(local) - m.apply(pose.transform(local))).norm(), 1e-15);
}

TEST(PoseFit, VelocityFromMotion) {
  Vec3 axis = Vec3(1, 2, -1).normalized();
  double angle = 0.05, dt = 1.0 / 60;
  Mat3 R = Eigen::AngleAxisd(angle, axis).toRotationMatrix();
  Vec3 pivot(0.2, 1.0, 0.3), shift(0.01, 0, -0.02), com(0.25, 1.1, 0.3);
  RigidMotion m = RigidMotion::about(pivot, R, shift);
  BodyVelocity v = velocity_from_motion(m, com, dt);
  EXPECT_LE((v.angular - axis * angle / dt).norm(), 1e-12);
  EXPECT_LE((v.linear - (R * com + m.t - com) / dt).norm(), 1e-12);
  // Tiny and zero rotations keep full accuracy and stay finite.
  Mat3 tiny = Eigen::AngleAxisd(1e-12, axis).toRotationMatrix();
  EXPECT_LE((rotation_vector(tiny) - axis * 1e-12).norm(), 1e-24);
  EXPECT_EQ(rotation_vector(Mat3(Mat3::Identity())), Vec3::Zero());
  EXPECT_NEAR(rotation_vector(Mat3(Eigen::AngleAxisd(M_PI, axis).toRotationMatrix())).norm(), M_PI, 1e-12);
  EXPECT_THROW(velocity_from_motion(m, com, 0.0), Error);
}

// The contact skin's press (docs/grasp.md "First touch"): each contact pushes, never pulls, until the body moves
// away at its needed speed there, by at most its impulse; an off-centre push turns the body; no mass, no motion.
TEST(SkinPress, PushesUpToTheNeededSpeedWithinTheImpulseAndNeverPulls) {
  InverseInertia body;
  body.inverse_mass = 1 / 0.1;  // 100 g
  body.inverse_inertia = Mat3::Identity() / (0.1 * 2.67e-5);  // a 4 cm cube: m a^2 / 6 with a = 4 cm
  SkinContact top;
  top.point = Vec3(0, 0.02, 0);
  top.normal = Vec3::UnitY();
  top.hand_velocity = Vec3(0, -0.05, 0);  // the hand comes down at 5 cm/s
  top.max_impulse = 1.0;
  BodyVelocity v = skin_press({top}, body, {});
  EXPECT_NEAR(v.linear.y(), -0.05, 1e-12);  // carried along at the hand's speed, not faster
  EXPECT_LE(v.angular.norm(), 1e-12);       // through the centre: no turn
  top.max_impulse = 0.001;                   // the pulp passes 1 mN s: 1 cm/s for 100 g
  v = skin_press({top}, body, {});
  EXPECT_NEAR(v.linear.y(), -0.01, 1e-12);
  BodyVelocity leaving;
  leaving.linear = Vec3(0, -0.2, 0);  // already moving away faster than the hand: nothing to do
  v = skin_press({top}, body, leaving);
  EXPECT_EQ(v.linear, leaving.linear);
  top.hand_velocity = Vec3(0, 0.05, 0);  // the hand lifts off: the skin does not pull the body after it
  v = skin_press({top}, body, {});
  EXPECT_EQ(v.linear, Vec3::Zero());
  SkinContact edge = top;  // off-centre: turns the body, and the contact point reaches the needed speed
  edge.point = Vec3(0.02, 0.02, 0);
  edge.hand_velocity = Vec3(0, -0.05, 0);
  edge.max_impulse = 1.0;
  v = skin_press({edge}, body, {}, 1);
  EXPECT_GT(v.angular.norm(), 0);
  EXPECT_NEAR((v.linear + v.angular.cross(edge.point)).dot(-edge.normal), 0.05, 1e-12);
  EXPECT_EQ(skin_press({edge}, InverseInertia{}, {}).linear, Vec3::Zero());  // static: immovable
}

// The physical push (PushModel::Physical) on one contact: the pulp pushes a free 100 g, 4 cm cube at an edge point
// while the hand moves into it and along its surface. Whatever the bound and the hand's speed, the impulse is
// within the pulp's bound and friction's cone, pushes (never pulls), leaves the contact point no faster than the
// hand into the body (along the surface the push's turn may outrun what friction can hold), and gives the body no more kinetic energy than the work the hand's point does
// (impulse . hand velocity; an inelastic push gives half of it to a body starting at rest).
TEST(SkinPress, FrictionStaysInTheConeAndNoPushGivesMoreThanTheHandDoes) {
  InverseInertia body;
  const double mass = 0.1;
  body.inverse_mass = 1 / mass;
  body.inverse_inertia = Mat3::Identity() / (mass * 2.67e-5);
  SkinContact c;
  c.point = Vec3(0.015, 0.02, -0.01);
  c.normal = Vec3::UnitY();
  c.friction = 0.5;
  for (double bound : {1e-5, 1e-3, 1.0})
    for (const Vec3& hand : {Vec3(0.1, -0.05, 0), Vec3(0.3, -0.01, 0.2), Vec3(0, -0.2, 0), Vec3(0.1, 0.05, 0)}) {
      c.max_impulse = bound;
      c.hand_velocity = hand;
      const BodyVelocity v = skin_press({c}, body, {});
      const Vec3 impulse = mass * v.linear;  // one contact: all of the body's momentum came through it
      const Vec3 in = -c.normal;
      const double pushed = impulse.dot(in);
      const Vec3 dragged = impulse - pushed * in;
      EXPECT_GE(pushed, 0) << "never pulls";
      EXPECT_LE(pushed, bound * (1 + 1e-12));
      EXPECT_LE(dragged.norm(), c.friction * pushed * (1 + 1e-12) + 1e-15) << "Coulomb";
      const Vec3 r = c.point - body.centre;
      const Vec3 point = v.linear + v.angular.cross(r);
      EXPECT_LE(point.dot(in), std::max(0.0, hand.dot(in)) + 1e-12) << "no faster than the hand into it";
      const double energy = 0.5 * mass * v.linear.squaredNorm() +
                            0.5 * v.angular.dot((body.inverse_inertia.inverse()) * v.angular);
      EXPECT_LE(energy, std::max(0.0, impulse.dot(hand)) + 1e-15) << "no more than the hand's work";
      if (hand.dot(in) <= 0) EXPECT_EQ(v.linear, Vec3::Zero()) << "a hand leaving the body does not move it";
    }
  // A body at rest under a still hand stays at rest; one sliding under it is slowed by friction, never reversed.
  c.hand_velocity = Vec3::Zero();
  c.max_impulse = 1.0;
  BodyVelocity v = skin_press({c}, body, {});
  EXPECT_EQ(v.linear, Vec3::Zero());
  EXPECT_EQ(v.angular, Vec3::Zero());
  BodyVelocity sliding;
  sliding.linear = Vec3(0.2, 0.01, 0);  // moving into the still hand above it and along it
  v = skin_press({c}, body, sliding);
  EXPECT_GE(v.linear.x(), 0) << "friction stops the slide at most";
  EXPECT_LT(v.linear.x(), 0.2);
}

// The same solve as the least displacement out of an overlap: unbounded, frictionless, from rest, the hand's
// "velocity" -normal * overlap. A contact through the centre moves the body straight out by the overlap.
TEST(SkinPress, TheLeastDisplacementOutOfAnOverlap) {
  InverseInertia body;
  body.inverse_mass = 10;
  body.inverse_inertia = Mat3::Identity() / (0.1 * 2.67e-5);
  SkinContact c;
  c.point = Vec3(0, 0.02, 0);
  c.normal = Vec3::UnitY();
  c.hand_velocity = -c.normal * 0.002;
  c.max_impulse = std::numeric_limits<double>::infinity();
  const BodyVelocity shift = skin_press({c}, body, {});
  EXPECT_NEAR(shift.linear.y(), -0.002, 1e-15);
  EXPECT_LE(shift.angular.norm(), 1e-15);
}
