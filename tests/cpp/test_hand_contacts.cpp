// Closed-form particle contacts against analytic and brute-force references, including degenerate centres.
#include "handsim/hand.h"

#include <gtest/gtest.h>

#include <map>
#include <random>

using namespace handsim;

namespace {

Pose body_pose() {
  Pose p;
  p.position = Vec3(0.1, 0.5, -0.2);
  p.orientation = Quat(Eigen::AngleAxisd(0.8, Vec3(1, 1, 0.2).normalized()));
  return p;
}

Eigen::Matrix3Xd random_centres(int n, double spread, const Pose& around, uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> u(-spread, spread);
  Eigen::Matrix3Xd c(3, n);
  for (int i = 0; i < n; ++i) c.col(i) = around.transform(Vec3(u(rng), u(rng), u(rng)));
  return c;
}

// Every contact: unit normal, centre = point + (radius - depth) * normal, depth in (0, ...].
void check_identities(const Eigen::Matrix3Xd& c, double r, const std::vector<ParticleContact>& cs) {
  for (const ParticleContact& k : cs) {
    ASSERT_TRUE(k.point.allFinite() && k.normal.allFinite() && std::isfinite(k.depth));
    EXPECT_NEAR(k.normal.norm(), 1.0, 1e-12);
    EXPECT_GT(k.depth, 0);
    EXPECT_LE((c.col(k.particle) - (k.point + (r - k.depth) * k.normal)).norm(), 1e-12);
  }
}

// Reference box signed distance: outside = distance to the clamped point; inside = -(distance to nearest face).
double box_sd(const Vec3& l, const Vec3& h) {
  Vec3 c = l.cwiseMax(-h).cwiseMin(h);
  if ((l - c).norm() > 0) return (l - c).norm();
  double m = 1e300;
  for (int k = 0; k < 3; ++k) m = std::min({m, h[k] - l[k], h[k] + l[k]});
  return -m;
}

std::vector<Vec3> box_corners(const Vec3& h) {
  std::vector<Vec3> v;
  for (int i = 0; i < 8; ++i) v.push_back(Vec3(i & 1 ? h.x() : -h.x(), i & 2 ? h.y() : -h.y(), i & 4 ? h.z() : -h.z()));
  return v;
}

}  // namespace

TEST(ParticleContacts, BoxMatchesTheReference) {
  const Vec3 h(0.05, 0.03, 0.08);
  const double r = 0.004;
  const Pose P = body_pose();
  Eigen::Matrix3Xd c = random_centres(20000, 0.1, P, 1);
  std::vector<ParticleContact> cs;
  collide_particles(c, r, ShapeDef::box(h), P, cs);
  check_identities(c, r, cs);
  std::vector<int> hit(c.cols(), -1);
  for (size_t i = 0; i < cs.size(); ++i) hit[cs[i].particle] = int(i);
  int inside = 0;
  for (int i = 0; i < c.cols(); ++i) {
    double sd = box_sd(P.inverse_transform(c.col(i)), h);
    if (sd < r) {
      ASSERT_GE(hit[i], 0);
      EXPECT_NEAR(cs[hit[i]].depth, r - sd, 1e-12);
      Vec3 lp = P.inverse_transform(cs[hit[i]].point);
      EXPECT_NEAR(box_sd(lp, h), 0, 1e-12);  // the point is on the surface
      inside += sd < 0;
    } else {
      EXPECT_EQ(hit[i], -1);
    }
  }
  EXPECT_GT(inside, 100);
  // Inside: the least-penetration face.
  Eigen::Matrix3Xd one(3, 1);
  one.col(0) = P.transform(Vec3(0.01, 0.025, -0.02));  // 5 mm below the +Y face, far from the others
  cs.clear();
  collide_particles(one, r, ShapeDef::box(h), P, cs);
  ASSERT_EQ(cs.size(), 1u);
  EXPECT_NEAR((cs[0].normal - P.orientation * Vec3::UnitY()).norm(), 0, 1e-12);
  EXPECT_NEAR(cs[0].depth, r + 0.005, 1e-12);
  // The exact centre of a cube: no NaN.
  one.col(0) = P.position;
  cs.clear();
  collide_particles(one, r, ShapeDef::box(Vec3::Constant(0.02)), P, cs);
  ASSERT_EQ(cs.size(), 1u);
  EXPECT_TRUE(cs[0].normal.allFinite());
  EXPECT_NEAR(cs[0].depth, r + 0.02, 1e-12);
}

TEST(ParticleContacts, SphereAnalyticAndCentre) {
  const double R = 0.05, r = 0.005;
  const Pose P = body_pose();
  Eigen::Matrix3Xd c = random_centres(20000, 0.07, P, 2);
  std::vector<ParticleContact> cs;
  collide_particles(c, r, ShapeDef::sphere(R), P, cs);
  check_identities(c, r, cs);
  size_t expected = 0;
  for (int i = 0; i < c.cols(); ++i) expected += (c.col(i) - P.position).norm() - R < r;
  EXPECT_EQ(cs.size(), expected);
  for (const ParticleContact& k : cs) {
    EXPECT_NEAR((k.point - P.position).norm(), R, 1e-12);
    EXPECT_NEAR(k.depth, r + R - (c.col(k.particle) - P.position).norm(), 1e-12);
  }
  Eigen::Matrix3Xd centre(3, 1);
  centre.col(0) = P.position;
  cs.clear();
  collide_particles(centre, r, ShapeDef::sphere(R), P, cs);
  ASSERT_EQ(cs.size(), 1u);
  EXPECT_NEAR(cs[0].depth, r + R, 1e-12);
  EXPECT_NEAR((cs[0].normal - P.orientation * Vec3::UnitY()).norm(), 0, 1e-12);
}

TEST(ParticleContacts, CapsuleAnalyticAndAxis) {
  const double R = 0.02, hh = 0.04, r = 0.005;
  const Pose P = body_pose();
  Eigen::Matrix3Xd c = random_centres(20000, 0.07, P, 3);
  std::vector<ParticleContact> cs;
  collide_particles(c, r, ShapeDef::capsule(R, hh), P, cs);
  check_identities(c, r, cs);
  // Reference: distance to the segment sampled finely (brute force), minus the radius.
  auto ref_sd = [&](const Vec3& w) {
    Vec3 l = P.inverse_transform(w);
    double best = 1e300;
    for (int i = 0; i <= 20000; ++i) best = std::min(best, (l - Vec3(0, -hh + 2 * hh * i / 20000.0, 0)).norm());
    return best - R;
  };
  for (size_t k = 0; k < cs.size(); k += 37) EXPECT_NEAR(cs[k].depth, r - ref_sd(c.col(cs[k].particle)), 1e-8);
  size_t expected = 0;
  for (int i = 0; i < c.cols(); ++i) {
    Vec3 l = P.inverse_transform(c.col(i));
    expected += (l - Vec3(0, std::clamp(l.y(), -hh, hh), 0)).norm() - R < r;
  }
  EXPECT_EQ(cs.size(), expected);
  // Centres on the axis, at a cap centre, and at the middle: finite, correct depth.
  Eigen::Matrix3Xd axis(3, 3);
  axis.col(0) = P.transform(Vec3(0, 0.01, 0));
  axis.col(1) = P.transform(Vec3(0, hh, 0));
  axis.col(2) = P.transform(Vec3(0, -hh, 0));
  cs.clear();
  collide_particles(axis, r, ShapeDef::capsule(R, hh), P, cs);
  ASSERT_EQ(cs.size(), 3u);
  check_identities(axis, r, cs);
  for (const ParticleContact& k : cs) EXPECT_NEAR(k.depth, r + R, 1e-12);
  EXPECT_NEAR((cs[1].normal - P.orientation * Vec3::UnitY()).norm(), 0, 1e-12);
  EXPECT_NEAR((cs[2].normal + P.orientation * Vec3::UnitY()).norm(), 0, 1e-12);
}

TEST(ParticleContacts, ConvexHullOfABoxEqualsTheBox) {
  const Vec3 h(0.05, 0.03, 0.08);
  const double r = 0.004;
  const Pose P = body_pose();
  std::vector<Vec3> pts = box_corners(h);
  pts.push_back(Vec3(0.01, 0.0, 0.02));  // an interior point the hull must ignore
  PreparedShape hull = prepare_shape(ShapeDef::convex_hull(pts));
  EXPECT_EQ(hull.planes.size(), 6u);  // coplanar triangles merged into faces
  Eigen::Matrix3Xd c = random_centres(20000, 0.1, P, 4);
  std::vector<ParticleContact> a, b;
  collide_particles(c, r, ShapeDef::box(h), P, a);
  collide_particles(c, r, hull, P, b);
  check_identities(c, r, b);
  ASSERT_EQ(a.size(), b.size());
  for (size_t i = 0; i < a.size(); ++i) {
    EXPECT_EQ(a[i].particle, b[i].particle);
    EXPECT_NEAR(a[i].depth, b[i].depth, 1e-12);
    EXPECT_LE((a[i].point - b[i].point).norm(), 1e-12);
  }
}

TEST(ParticleContacts, ConvexHullOfATetrahedronBruteForce) {
  std::vector<Vec3> t = {{0, 0, 0}, {0.1, 0, 0}, {0, 0.1, 0}, {0, 0, 0.1}};
  const double r = 0.01;
  PreparedShape hull = prepare_shape(ShapeDef::convex_hull(t));
  EXPECT_EQ(hull.planes.size(), 4u);
  Pose P;
  Eigen::Matrix3Xd c = random_centres(5000, 0.08, Pose{Vec3(0.03, 0.03, 0.03), Quat::Identity()}, 5);
  std::vector<ParticleContact> cs;
  collide_particles(c, r, hull, P, cs);
  check_identities(c, r, cs);
  // Outside the tetrahedron the closest point is on its 4 triangles; inside, the nearest plane.
  for (const ParticleContact& k : cs) {
    Vec3 x = c.col(k.particle);
    bool inside = x.minCoeff() >= 0 && x.sum() <= 0.1;
    double sd = r - k.depth;
    if (inside) {
      double m = std::min({x.x(), x.y(), x.z(), (0.1 - x.sum()) / std::sqrt(3.0)});
      EXPECT_NEAR(sd, -m, 1e-12);
    } else {
      EXPECT_GT(sd, -1e-15);
    }
  }
}

TEST(ParticleContacts, TriangleMeshShellOfABoxMatchesOutside) {
  const Vec3 h(0.05, 0.03, 0.08);
  const double r = 0.004;
  const Pose P = body_pose();
  std::vector<Vec3> v = box_corners(h);
  std::vector<int> idx = {0, 2, 1, 1, 2, 3, 4, 5, 6, 5, 7, 6, 0, 1, 4, 1, 5, 4,
                          2, 6, 3, 3, 6, 7, 0, 4, 2, 2, 4, 6, 1, 3, 5, 3, 7, 5};
  Eigen::Matrix3Xd c = random_centres(20000, 0.1, P, 6);
  std::vector<ParticleContact> a, b;
  collide_particles(c, r, ShapeDef::box(h), P, a);
  collide_particles(c, r, ShapeDef::triangle_mesh(v, idx), P, b);
  check_identities(c, r, b);
  std::map<int, ParticleContact> bm;
  for (auto& k : b) bm[k.particle] = k;
  int outside = 0;
  for (auto& k : a) {
    double sd = r - k.depth;
    if (sd <= 1e-9) continue;  // inside: a shell reports the unsigned distance instead
    ++outside;
    ASSERT_TRUE(bm.count(k.particle));
    EXPECT_NEAR(bm[k.particle].depth, k.depth, 1e-12);
  }
  EXPECT_GT(outside, 100);
}

TEST(ParticleContacts, BoundsAndErrors) {
  Vec3 lo, hi;
  Pose P = body_pose();
  shape_world_bounds(ShapeDef::box(Vec3(0.05, 0.03, 0.08)), P, lo, hi);
  for (const Vec3& corner : box_corners(Vec3(0.05, 0.03, 0.08))) {
    Vec3 w = P.transform(corner);
    EXPECT_TRUE((w.array() >= lo.array() - 1e-15).all() && (w.array() <= hi.array() + 1e-15).all());
  }
  EXPECT_TRUE(bounds_overlap(lo, hi, hi - Vec3::Constant(0.001), hi + Vec3::Constant(1)));
  EXPECT_FALSE(bounds_overlap(lo, hi, hi + Vec3::Constant(0.001), hi + Vec3::Constant(1)));
  std::vector<ParticleContact> cs;
  Eigen::Matrix3Xd c = Eigen::Matrix3Xd::Zero(3, 1);
  try {
    collide_particles(c, -0.001, ShapeDef::sphere(0.1), P, cs);
    FAIL();
  } catch (const Error& e) {
    EXPECT_EQ(e.argument(), "radius");
  }
  EXPECT_THROW(collide_particles(c, 0.001, ShapeDef::sphere(-0.1), P, cs), Error);
}
