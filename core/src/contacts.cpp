// Closed-form particle contacts: the default narrow phase. Each centre is taken into the body frame, the
// signed distance to the shape and the closest surface point are computed there, and results go back to world.
#include "contacts.h"

#include "grasp.h"
#include "simd4.h"
#include "skinning.h"
#include "validate.h"
#include "world_impl.h"

#include <LinearMath/btConvexHullComputer.h>

#include <algorithm>
#include <cmath>
#include <limits>

namespace handsim {
namespace {

// Signed distance of a local point to a shape, with the closest surface point and the outward normal there.
struct Closest {
  double sd;
  Vec3 point, normal;
};

Closest box_closest(const Vec3& l, const Vec3& h) {
  Vec3 q = l.cwiseAbs() - h;
  if ((q.array() > 0).any()) {
    Vec3 c = l.cwiseMax(-h).cwiseMin(h);
    Vec3 d = l - c;
    double n = d.norm();
    return {n, c, d / n};
  }
  // Inside: the face of least penetration (largest q); ties pick the lowest axis.
  int k = 0;
  for (int i = 1; i < 3; ++i)
    if (q[i] > q[k]) k = i;
  double s = l[k] >= 0 ? 1.0 : -1.0;
  Vec3 c = l;
  c[k] = s * h[k];
  Vec3 n = Vec3::Zero();
  n[k] = s;
  return {q[k], c, n};
}

Closest sphere_closest(const Vec3& l, double r, const Vec3& fallback) {
  double d = l.norm();
  Vec3 n = d > 1e-12 ? Vec3(l / d) : fallback;  // the centre itself: any direction is right, pick a fixed one
  return {d - r, r * n, n};
}

Closest capsule_closest(const Vec3& l, double r, double hh) {
  Vec3 axis(0, std::clamp(l.y(), -hh, hh), 0);
  Vec3 v = l - axis;
  double d = v.norm();
  Vec3 n;
  if (d > 1e-12) n = v / d;
  else if (std::abs(l.y()) < hh) n = Vec3::UnitX();    // on the axis inside the core: any radial direction
  else n = Vec3(0, l.y() >= 0 ? 1.0 : -1.0, 0);  // at a cap centre: along the axis
  return {d - r, axis + r * n, n};
}

// Closest point on triangle abc to p (Ericson, Real-Time Collision Detection 5.1.5).
Vec3 closest_on_triangle(const Vec3& p, const Vec3& a, const Vec3& b, const Vec3& c) {
  Vec3 ab = b - a, ac = c - a, ap = p - a;
  double d1 = ab.dot(ap), d2 = ac.dot(ap);
  if (d1 <= 0 && d2 <= 0) return a;
  Vec3 bp = p - b;
  double d3 = ab.dot(bp), d4 = ac.dot(bp);
  if (d3 >= 0 && d4 <= d3) return b;
  double vc = d1 * d4 - d3 * d2;
  if (vc <= 0 && d1 >= 0 && d3 <= 0) return a + d1 / (d1 - d3) * ab;
  Vec3 cp = p - c;
  double d5 = ab.dot(cp), d6 = ac.dot(cp);
  if (d6 >= 0 && d5 <= d6) return c;
  double vb = d5 * d2 - d1 * d6;
  if (vb <= 0 && d2 >= 0 && d6 <= 0) return a + d2 / (d2 - d6) * ac;
  double va = d3 * d6 - d5 * d4;
  if (va <= 0 && (d4 - d3) >= 0 && (d5 - d6) >= 0) return b + (d4 - d3) / ((d4 - d3) + (d5 - d6)) * (c - b);
  double denom = 1 / (va + vb + vc);
  return a + ab * (vb * denom) + ac * (vc * denom);
}

// Nearest point over a triangle list (brute force with per-triangle bounds culling when given).
bool nearest_on_triangles(const Vec3& l, const std::vector<Vec3>& v, const std::vector<int>& tri, double reach,
                          const std::vector<Vec3>* lo, const std::vector<Vec3>* hi, Vec3& best_point,
                          int& best_tri) {
  double best = reach * reach;
  best_tri = -1;
  for (size_t t = 0; t < tri.size() / 3; ++t) {
    if (lo && ((l.array() < (*lo)[t].array() - reach).any() || (l.array() > (*hi)[t].array() + reach).any()))
      continue;
    Vec3 c = closest_on_triangle(l, v[tri[3 * t]], v[tri[3 * t + 1]], v[tri[3 * t + 2]]);
    double d2 = (l - c).squaredNorm();
    if (d2 < best) {
      best = d2;
      best_point = c;
      best_tri = int(t);
    }
  }
  return best_tri >= 0;
}

// Returns false when the centre is farther than `radius` from the shape (no contact possible).
bool closest_on_shape(const PreparedShape& ps, const Vec3& l, double radius, Closest& out) {
  const ShapeDef& s = ps.shape;
  switch (s.type) {
    case ShapeType::Box: out = box_closest(l, s.half_extents); return true;
    case ShapeType::Sphere: out = sphere_closest(l, s.radius, Vec3::UnitY()); return true;
    case ShapeType::Capsule: out = capsule_closest(l, s.radius, s.half_height); return true;
    case ShapeType::ConvexHull: {
      // Inside a convex polytope the distance to the boundary is the distance to the nearest face plane.
      double sd = -1e300;
      int k = 0;
      for (size_t i = 0; i < ps.planes.size(); ++i) {
        double d = ps.planes[i].head<3>().dot(l) - ps.planes[i][3];
        if (d > sd) {
          sd = d;
          k = int(i);
        }
      }
      if (sd >= radius) return false;  // the plane distance bounds the true distance from below
      if (sd <= 0) {
        Vec3 n = ps.planes[k].head<3>();
        out = {sd, l - sd * n, n};
        return true;
      }
      Vec3 c;
      int t;
      if (!nearest_on_triangles(l, ps.hull_vertices, ps.hull_triangles, radius, nullptr, nullptr, c, t)) return false;
      double d = (l - c).norm();
      out = {d, c, d > 1e-12 ? Vec3((l - c) / d) : Vec3(ps.planes[k].head<3>())};
      return true;
    }
    case ShapeType::TriangleMesh: {
      Vec3 c;
      int t;
      if (!nearest_on_triangles(l, s.points, s.indices, radius, &ps.tri_lo, &ps.tri_hi, c, t)) return false;
      double d = (l - c).norm();
      Vec3 n;
      if (d > 1e-12) {
        n = (l - c) / d;
      } else {
        const Vec3 &a = s.points[s.indices[3 * t]], &b = s.points[s.indices[3 * t + 1]],
                   &e = s.points[s.indices[3 * t + 2]];
        n = (b - a).cross(e - a).normalized();
      }
      out = {d, c, n};
      return true;
    }
  }
  return false;
}

void prepare_hull(PreparedShape& ps) {
  const auto& pts = ps.shape.points;
  std::vector<double> coords;
  for (const Vec3& p : pts) coords.insert(coords.end(), {p.x(), p.y(), p.z()});
  btConvexHullComputer hc;
  hc.compute(coords.data(), 3 * sizeof(double), int(pts.size()), 0, 0);
  // Bullet returns the hull vertices in single precision: map each back to the exact input point.
  std::vector<int> exact(hc.vertices.size());
  for (int i = 0; i < hc.vertices.size(); ++i) {
    Vec3 v(hc.vertices[i].x(), hc.vertices[i].y(), hc.vertices[i].z());
    double best = 1e300;
    for (size_t j = 0; j < pts.size(); ++j) {
      double d = (pts[j] - v).squaredNorm();
      if (d < best) {
        best = d;
        exact[i] = int(j);
      }
    }
    ps.hull_vertices.push_back(pts[exact[i]]);
  }
  for (int f = 0; f < hc.faces.size(); ++f) {
    std::vector<int> poly;
    const btConvexHullComputer::Edge* start = &hc.edges[hc.faces[f]];
    const btConvexHullComputer::Edge* e = start;
    do {
      poly.push_back(e->getSourceVertex());
      e = e->getNextEdgeOfFace();
    } while (e != start);
    // Newell's normal of the (counter-clockwise from outside) polygon, offset through its vertices.
    Vec3 n = Vec3::Zero(), centroid = Vec3::Zero();
    for (size_t i = 0; i < poly.size(); ++i) {
      const Vec3 &a = ps.hull_vertices[poly[i]], &b = ps.hull_vertices[poly[(i + 1) % poly.size()]];
      n += Vec3((a.y() - b.y()) * (a.z() + b.z()), (a.z() - b.z()) * (a.x() + b.x()), (a.x() - b.x()) * (a.y() + b.y()));
      centroid += a;
    }
    if (n.norm() < 1e-15) continue;
    n.normalize();
    centroid /= double(poly.size());
    double d = -1e300;
    for (int v : poly) d = std::max(d, n.dot(ps.hull_vertices[v]));
    ps.planes.push_back(Eigen::Vector4d(n.x(), n.y(), n.z(), d));
    for (size_t i = 1; i + 1 < poly.size(); ++i) ps.hull_triangles.insert(ps.hull_triangles.end(), {poly[0], poly[i], poly[i + 1]});
  }
  if (ps.planes.size() < 4) validate::fail("shape.points", "the convex hull is flat (needs a volume)");
}

}  // namespace

PreparedShape prepare_shape(const ShapeDef& shape, const std::string& argument) {
  validate_shape(shape, argument);
  PreparedShape ps;
  ps.shape = shape;
  shape_local_bounds(shape, ps.local_lo, ps.local_hi);
  if (shape.type == ShapeType::ConvexHull) prepare_hull(ps);
  if (shape.type == ShapeType::TriangleMesh) {
    for (size_t t = 0; t < shape.indices.size(); t += 3) {
      const Vec3 &a = shape.points[shape.indices[t]], &b = shape.points[shape.indices[t + 1]],
                 &c = shape.points[shape.indices[t + 2]];
      ps.tri_lo.push_back(a.cwiseMin(b).cwiseMin(c));
      ps.tri_hi.push_back(a.cwiseMax(b).cwiseMax(c));
    }
  }
  return ps;
}

void collide_particle_ranges(const Eigen::Matrix3Xd& centres, const std::vector<std::pair<int, int>>& ranges,
                             double radius, const PreparedShape& ps, const Pose& body_pose,
                             std::vector<ParticleContact>& out) {
  validate::non_negative(radius, "radius");
  const Mat3 R = body_pose.orientation.normalized().toRotationMatrix();
  const Vec3 lo = ps.local_lo.array() - radius, hi = ps.local_hi.array() + radius;
  for (const auto& range : ranges)
    for (Eigen::Index i = range.first; i < range.second; ++i) {
      const Vec3 l = R.transpose() * (centres.col(i) - body_pose.position);
      if ((l.array() < lo.array()).any() || (l.array() > hi.array()).any()) continue;  // cheap local bounds test
      Closest c;
      if (!closest_on_shape(ps, l, radius, c)) continue;
      double depth = radius - c.sd;
      if (depth <= 0) continue;
      out.push_back({int(i), R * c.point + body_pose.position, R * c.normal, depth});
    }
}

void collide_particles(const Eigen::Matrix3Xd& centres, double radius, const PreparedShape& ps,
                       const Pose& body_pose, std::vector<ParticleContact>& out) {
  collide_particle_ranges(centres, {{0, int(centres.cols())}}, radius, ps, body_pose, out);
}

void collide_particles(const Eigen::Matrix3Xd& centres, double radius, const ShapeDef& shape,
                       const Pose& body_pose, std::vector<ParticleContact>& out) {
  collide_particles(centres, radius, prepare_shape(shape), body_pose, out);
}

bool entry_face(const PreparedShape& ps, const Vec3& l, const Vec3& u, double max_time, Vec3& normal,
                double& offset) {
  // The outputs are written only on success: a caller keeps a face it was given when no crossing lies within
  // max_time (the far face of a spinning base, found 18 cm back along its velocity, was once left in them and
  // then kept by keep_entry_faces frame after frame).
  double best = std::numeric_limits<double>::infinity();
  Vec3 best_normal = normal;
  double best_offset = offset;
  auto consider = [&](const Vec3& n, double d) {  // plane n . x = d; going back along -u leaves through it?
    const double away = -n.dot(u);
    if (away <= 0) return;
    const double t = (d - n.dot(l)) / away;
    if (t < best) {
      best = t;
      best_normal = n;
      best_offset = d;
    }
  };
  if (ps.shape.type == ShapeType::Box) {
    for (int k = 0; k < 3; ++k)
      for (double side : {-1.0, 1.0}) consider(side * Vec3::Unit(k), ps.shape.half_extents[k]);
  } else if (ps.shape.type == ShapeType::ConvexHull) {
    for (const Eigen::Vector4d& p : ps.planes) consider(p.head<3>(), p[3]);
  }
  if (best > max_time) return false;
  normal = best_normal;
  offset = best_offset;
  return true;
}

void local_box_in_world(const Vec3& llo, const Vec3& lhi, const Pose& pose, Vec3& lo, Vec3& hi) {
  const Mat3 R = pose.orientation.normalized().toRotationMatrix();
  const Vec3 c = pose.transform(0.5 * (llo + lhi));
  const Vec3 e = R.cwiseAbs() * (0.5 * (lhi - llo));
  lo = c - e;
  hi = c + e;
}

void shape_world_bounds(const ShapeDef& shape, const Pose& pose, Vec3& lo, Vec3& hi) {
  Vec3 llo, lhi;
  shape_local_bounds(shape, llo, lhi);
  local_box_in_world(llo, lhi, pose, lo, hi);
}

namespace {

// Contact persistence through thin bodies. The closed form answers with the *nearest* face, so a particle
// pushed more than half-way into a 1.5 cm lid is answered with the far face and pushes the lid the wrong way
// (the experiments saw a lid held past its limit slammed shut at 650 deg/s; recorded Leap fists closing on a
// cube never grasped it, their fingertips answered with the far face). A particle keeps the face it entered through for as long as its
// centre stays inside the body, and its contact is measured against that face's plane. The face is taken
// afresh when the centre is outside (a finger sliding round an edge changes face legitimately); a
// centre already inside at its first contact (a fast hand, a falling lid) takes the face it crossed, found
// by going back along its velocity relative to the body. A particle whose centre has just come out on the far
// side still keeps its entry face: it crossed the body, it did not come from there.
// Two faces whose outward normals are further apart than this are on opposite sides of the body (a box's
// adjacent faces are at 0, its opposite ones at -1).
constexpr double kOppositeFaces = -0.5;
// How many frames back along its relative velocity a first contact's crossing may lie (see entry_face).
constexpr double kEntryFrames = 2.0;

// The hand's motion keep_entry_faces reads: its particles' own where the world keeps the bones' history.
HandMotion motion_of(const WorldDef& def, const HandSlot& h) {
  if (!keeps_articulation(def)) return {h.history};
  return {h.history, &h.articulation, h.model.get(), def.grasp.velocity_window_s, def.grasp.velocity_window};
}

}  // namespace

void keep_entry_faces(const Eigen::Matrix3Xd& centres, double radius, const PreparedShape& shape, const Pose& pose,
                      const BodyVelocity& body, const HandMotion& hand, double dt,
                      const std::vector<EntryFace>& previous, std::vector<EntryFace>& faces,
                      std::vector<ParticleContact>& contacts) {
  faces.clear();
  if (contacts.empty()) return;
  const Mat3 R = pose.orientation.normalized().toRotationMatrix();
  // The palm's motion relative to the body, once per pair and only when a particle's motion is read with no
  // bones' history: the hand's velocity estimate is a least-squares slope over its history, too dear to
  // evaluate per contact (hundreds on a pinched lid).
  Vec3 dv, dw;
  bool palm_relative = false;
  auto prev = previous.begin();
  for (ParticleContact& c : contacts) {  // both lists are sorted by particle
    // The next face is most often the one (the full pass's contacts are most of the faces); further on it is
    // found by bisection (the hold path's two witnesses among a held lid's 255 faces).
    if (prev != previous.end() && prev->particle < c.particle && ++prev != previous.end() && prev->particle < c.particle)
      prev = std::lower_bound(prev, previous.end(), c.particle, [](const EntryFace& f, int p) { return f.particle < p; });
    const Vec3 x = centres.col(c.particle);
    // The centre in body coordinates, for the particles that may have crossed the body only (as `relative`).
    auto local = [&] { return Vec3(R.transpose() * (x - pose.position)); };
    const bool inside = c.depth > radius;  // the centre is behind the surface
    EntryFace face{c.particle, R.transpose() * c.normal, 0};
    face.offset = face.normal.dot(R.transpose() * (c.point - pose.position));
    const bool touched_before = prev != previous.end() && prev->particle == c.particle;
    // Only the particles that may have crossed the body need their motion relative to it (most contacts of a
    // held body are neither inside nor leaving, and skip this). A particle moves along its own path: with the bones'
    // history that is its bone's motion, the finger's flexion with the palm's. The palm's rigid motion alone misses a
    // fingertip curling through a lid under a still palm: its reach was a radius, and a tip going 5 mm a 30 Hz frame
    // came out of the 1.5 cm lid answered by the far face, where at 60 Hz it kept its entry face (docs/grasp.md "Why
    // a push depends on the frame rate").
    auto relative = [&] {
      if (hand.bones == nullptr) {
        if (!palm_relative) {
          const BodyVelocity hand_at_body = hand.palm.attached_body_velocity(pose.position);
          dv = hand_at_body.linear - body.linear;
          dw = hand_at_body.angular - body.angular;
          palm_relative = true;
        }
        return Vec3(dv + dw.cross(x - pose.position));
      }
      return Vec3(hand.bones->point_velocity(*hand.model, c.particle, x, hand.span, hand.most) -
                  (body.linear + body.angular.cross(x - pose.position)));
    };
    // How much deeper the entry face may say a particle coming out on the far side is than last frame: as far
    // as it moved relative to the body in two frames (slack for the lag of the velocity estimate), plus a
    // radius. More and it did not cross the body this frame (an 18 cm base, knocked spinning under the
    // fingers of the experiments' left hand, was thrown 13 cm by two particles answered with its far face).
    auto reach = [&] { return relative().norm() * kEntryFrames * dt + radius; };
    bool replaced = false;
    if (touched_before && (inside || (prev->crossing && prev->normal.dot(face.normal) < kOppositeFaces &&
                                      radius - (prev->normal.dot(local()) - prev->offset) <= prev->depth + reach()))) {
      // Inside, or leaving through the far side: a particle that was inside (or leaving) last frame and is now
      // nearest the face opposite the one it entered through, within its reach, has crossed the body, and
      // answering it with that face would push the body back the way the hand came (a hand driven past a
      // lid's stop flung the lid shut). One that only touched the near face from outside has not crossed
      // anything.
      face = *prev;
      replaced = true;
    } else if (inside && hand.palm.has_velocity()) {
      // A centre inside at its first contact crossed the surface within the last frame; two frames of slack
      // for the lag of the velocity estimate (a 4-sample slope).
      replaced = entry_face(shape, local(), R.transpose() * relative(), kEntryFrames * dt, face.normal, face.offset);
    }
    face.crossing = inside || replaced;
    if (replaced) {
      const Vec3 l = local();
      const double distance = face.normal.dot(l) - face.offset;  // < 0 behind the face
      c.normal = R * face.normal;
      c.point = R * (l - distance * face.normal) + pose.position;
      c.depth = radius - distance;
    }
    face.depth = c.depth;
    faces.push_back(face);
  }
}

// --- the hold path (docs/grasp.md "The hold path") ---
//
// A held body needs its contacts for one decision each frame: whether the hand still holds it (eq. 3 with
// release_distance: one opposing pair). While the hand is still on it -- every particle within kHoldStill of
// where it was, in the body's frame, at the last full pass (the anchor) -- the witness pair that proved the grasp
// is skinned and collided alone, and if it still opposes that is the answer the full pass would give
// (hand_intent tries the witness first). The other particles are where they were at the anchor, so their entry
// faces are carried over from it; their contacts and the deformation are made from the step's own numbers
// (complete_contacts) only when something reads them. A witness that lets go takes the full pass in the same
// step.

namespace {

// A bone's transform (bind to world) as bind to the frame of a body whose world-to-body rotation is Rt.
BoneTransform in_body(const Mat3& Rt, const Vec3& origin, const BoneTransform& bone) {
  BoneTransform m;
  m.leftCols<3>() = Rt * bone.leftCols<3>();
  m.col(3) = Rt * (bone.col(3) - origin);
  return m;
}

// A bone's move since `then` (its transform in the body frame then): |dR| reach + |dR j + dt|, dR and dt the
// change of its transform in the body frame (in_body), j its joint (holds_still).
double bone_move(const Mat3& Rt, const Vec3& origin, const BoneTransform& bone, const BoneTransform& then,
                 const Vec3& joint, double reach) {
  const BoneTransform now = in_body(Rt, origin, bone);
  const Mat3 dR = now.leftCols<3>() - then.leftCols<3>();
  const Vec3 dj = dR * joint + (now.col(3) - then.col(3));
  return dR.norm() * reach + dj.norm();
}

#ifdef HANDSIM_AVX2_KERNELS
using simd4::V4;

// bone_move of the bones now[0..3] (from bone `first` on) at once, lane l for now[l], with bone_move's bits: in_body's products and dR j
// summed as Eigen sums them (row_times), dR.norm() as its SSE2 sum of the nine squares (column-major)
// (((s0 + s2) + (s4 + s6)) + ((s1 + s3) + (s5 + s7))) + s8, dj.norm() as (x x + y y) + z z.
HANDSIM_AVX2 V4 bone_moves(const Mat3& Rt, const Vec3& origin, const BoneTransform* const* now,
                           const BoneTransform* const* then, const HandReach& reach, int first) {
  V4 b[12], t[12], dR[9], dj[3], s[9];
  simd4::load_bones(now, b);
  simd4::load_bones(then, t);
  for (int c = 0; c < 3; ++c)
    for (int i = 0; i < 3; ++i) dR[3 * c + i] = simd4::row_times(Rt, i, b[3 * c], b[3 * c + 1], b[3 * c + 2]) - t[3 * c + i];
  const V4 px = b[9] - simd4::splat(origin.x()), py = b[10] - simd4::splat(origin.y()),
           pz = b[11] - simd4::splat(origin.z());
  const V4 jx = simd4::load(&reach.lanes[0][first]), jy = simd4::load(&reach.lanes[1][first]),
           jz = simd4::load(&reach.lanes[2][first]);
  for (int i = 0; i < 3; ++i) {
    const V4 dt = simd4::row_times(Rt, i, px, py, pz) - t[9 + i];
    const V4 a = dR[i] * jx, bb = dR[3 + i] * jy, c = dR[6 + i] * jz;
    dj[i] = (i < 2 ? (a + bb) + c : a + (bb + c)) + dt;
  }
  for (int e = 0; e < 9; ++e) s[e] = dR[e] * dR[e];
  const V4 rotation = simd4::sqrt((((s[0] + s[2]) + (s[4] + s[6])) + ((s[1] + s[3]) + (s[5] + s[7]))) + s[8]);
  const V4 joint = simd4::sqrt((dj[0] * dj[0] + dj[1] * dj[1]) + dj[2] * dj[2]);
  return rotation * simd4::load(&reach.lanes[3][first]) + joint;  // (-inf for the bones the caller skips)
}

// bones_within_scalar four bones at a time (the last block: bones 24, 25 and 25 twice).
__attribute__((target("avx2"))) bool bones_within_avx2(const Mat3& Rt, const Vec3& origin,
                                                       const std::array<BoneTransform, kHandJointCount>& bones,
                                                       const BoneTransform* then, const HandReach& reach,
                                                       double limit, double* moves) {
  static_assert(kHandJointCount == 26, "six blocks of four and one of two");
  for (int first = 0; first < kHandJointCount; first += 4) {
    const int k[4] = {first, first + 1, std::min(first + 2, kHandJointCount - 1),
                      std::min(first + 3, kHandJointCount - 1)};
    const BoneTransform* const now[4] = {&bones[k[0]], &bones[k[1]], &bones[k[2]], &bones[k[3]]};
    const BoneTransform* const old[4] = {&then[k[0]], &then[k[1]], &then[k[2]], &then[k[3]]};
    const V4 m = bone_moves(Rt, origin, now, old, reach, first);
    for (int l = 0; l < 4 && first + l < kHandJointCount; ++l) {
      if (reach.reach[first + l] < 0) continue;  // moves no particle
      moves[first + l] = m[l];
      if (!(m[l] <= limit)) return false;
    }
  }
  return true;
}
#endif

}  // namespace

bool bones_within(const Mat3& Rt, const Vec3& origin, const std::array<BoneTransform, kHandJointCount>& bones, const BoneTransform* then,
                  const HandReach& reach, double limit, double* moves) {
#ifdef HANDSIM_AVX2_KERNELS
  if (simd4::has_avx2()) return bones_within_avx2(Rt, origin, bones, then, reach, limit, moves);
#endif
  return bones_within_scalar(Rt, origin, bones, then, reach, limit, moves);
}

bool bones_within_scalar(const Mat3& Rt, const Vec3& origin, const std::array<BoneTransform, kHandJointCount>& bones, const BoneTransform* then,
                         const HandReach& reach, double limit, double* moves) {
  for (int k = 0; k < kHandJointCount; ++k) {
    if (reach.reach[k] < 0) continue;  // moves no particle
    moves[k] = bone_move(Rt, origin, bones[k], then[k], reach.bind_joint[k], reach.reach[k]);
    if (!(moves[k] <= limit)) return false;
  }
  return true;
}

// Whether the pair is held by its hand, with a witness and an anchor, and no particle has moved more than
// kHoldStill relative to the body since the anchor: per bone, a point p blended from it moved by
// dR (p - j) + (dR j + dt), at most |dR| reach + |dR j + dt| (reach: its particles' farthest from its joint j).
bool HandParticles::holds_still(const HandSlot& h, const Body& b, const HandBodyPair& pair) const {
  const uint32_t hand = uint32_t(&h - hands.data());
  if (pair.anchor.size() != kHandJointCount || !pair.tracker.grasped() || !b.held_by(hand) || pair.witness[0] < 0 ||
      pair.witness[0] == pair.witness[1])
    return false;
  std::vector<BoneTransform>& anchored = pair.anchor_in_body;
  if (anchored.size() != size_t(kHandJointCount)) {
    const Mat3 At = pair.anchor_pose.orientation.normalized().toRotationMatrix().transpose();
    anchored.clear();
    for (const BoneTransform& bone : pair.anchor) anchored.push_back(in_body(At, pair.anchor_pose.position, bone));
  }
  const Mat3 Rt = b.pose.orientation.normalized().toRotationMatrix().transpose();
  double moves[kHandJointCount];
  return bones_within(Rt, b.pose.position, h.state.bones, anchored.data(), h.reach, kHoldStill, moves);
}

// The witness pass of a still pair: its two particles (skinned alone in pose_hands) against the body, as the full
// pass would collide them. True when both touch and still oppose: the pair's contacts are then the two, its
// entry faces the anchor's with the witnesses' renewed, and the rest is made when read (lazy).
bool HandParticles::hold_by_witness(uint32_t hi, uint32_t bi, HandBodyPair& pair, double dt) {
  const HandSlot& h = hands[hi];
  const Body& b = bodies[bi];
  const double radius = h.model->particle_radius, margin = def.grasp.release_distance;
  const int first = std::min(pair.witness[0], pair.witness[1]), second = std::max(pair.witness[0], pair.witness[1]);
  std::vector<std::pair<int, int>>& ranges = scratch.ranges;
  ranges.assign({{first, first + 1}, {second, second + 1}});
  std::vector<ParticleContact>& found = scratch.complete;
  found.clear();
  collide_particle_ranges(h.state.tracked_positions, ranges, radius + margin, b.prepared, b.pose, found);
  if (found.size() != 2) return false;
  for (ParticleContact& c : found) c.depth -= margin;
  keep_entry_faces(h.state.tracked_positions, radius, b.prepared, b.pose, {b.linear, b.angular}, motion_of(def, h), dt,
                   pair.previous_faces, scratch.faces, found);
  if (!(found[0].normal.dot(found[1].normal) < def.grasp.cos_threshold)) return false;  // as witness_opposes
  // The entry faces are the previous ones with the witnesses' renewed. The previous list itself is moved over
  // rather than copied (hundreds of faces on a pinched lid) and the witnesses' old faces kept aside:
  // complete_contacts puts the previous list back together when something reads the contacts.
  std::array<std::vector<EntryFace>::iterator, 2> at;
  for (size_t k = 0; k < 2; ++k) {
    at[k] = std::lower_bound(pair.previous_faces.begin(), pair.previous_faces.end(), scratch.faces[k].particle,
                             [](const EntryFace& f, int p) { return f.particle < p; });
    if (at[k] == pair.previous_faces.end() || at[k]->particle != scratch.faces[k].particle)
      return false;  // not touching at the anchor
  }
  for (size_t k = 0; k < 2; ++k) {
    pair.witness_faces_before[k] = *at[k];
    *at[k] = scratch.faces[k];
  }
  pair.entry_faces.swap(pair.previous_faces);  // (iterators stay with their elements)
  pair.contacts.swap(found);
  pair.lazy = true;
  pair.contact_pose = b.pose;
  pair.contact_velocity = {b.linear, b.angular};
  pair.contact_dt = dt;
  return true;
}

// The full contacts of the hand's lazy pairs, as the full pass of their step would have made them (its bones,
// history, previous faces, and the body's pose and velocity then), and the hand's deformation from them.
// Changes no state: the entry faces stay the carried ones, so reading does not change the future.
void HandParticles::complete_contacts(uint32_t hi) {
  bool any = false;
  HandSlot& h = hands[hi];
  for (auto it = pairs.lower_bound({hi, 0}); it != pairs.end() && it->first.first == hi; ++it) {
    HandBodyPair& pair = it->second;
    if (!pair.lazy) continue;
    const Body& b = bodies[it->first.second];
    // The previous faces as hold_by_witness found them: the carried ones with the witnesses' old faces back.
    pair.previous_faces = pair.entry_faces;
    for (const EntryFace& f : pair.witness_faces_before)
      *std::lower_bound(pair.previous_faces.begin(), pair.previous_faces.end(), f.particle,
                        [](const EntryFace& e, int p) { return e.particle < p; }) = f;
    refresh_particles(h, false);  // every particle, with the same bits as the groups in reach
    const double radius = h.model->particle_radius, margin = def.grasp.release_distance;
    Vec3 lo, hi_b;
    local_box_in_world(b.prepared.local_lo, b.prepared.local_hi, pair.contact_pose, lo, hi_b);
    near_particle_ranges(h, radius + margin, lo, hi_b, scratch.ranges);
    std::vector<ParticleContact>& found = scratch.complete;
    found.clear();
    collide_particle_ranges(h.state.tracked_positions, scratch.ranges, radius + margin, b.prepared, pair.contact_pose,
                            found);
    for (ParticleContact& c : found) c.depth -= margin;
    keep_entry_faces(h.state.tracked_positions, radius, b.prepared, pair.contact_pose, pair.contact_velocity, motion_of(def, h),
                     pair.contact_dt, pair.previous_faces, scratch.faces, found);
    pair.contacts.swap(found);
    pair.lazy = false;
    any = true;
  }
  if (any) deform_hand(hi);
}

void HandParticles::complete_all_contacts() {
  for (uint32_t hi = 0; hi < hands.size(); ++hi)
    if (hands[hi].alive) complete_contacts(hi);
}

namespace {
void collide_bullet_particles(HandParticles& particles, uint64_t body_version, uint32_t hi,
                              std::vector<std::vector<ParticleContact>>& per_body);
}  // namespace

// --- line 3: detect hand collision and contact particles ---
StageReport detect_contacts(HandParticles& particles, uint64_t body_version, double dt) {
  const WorldDef& def = particles.def;
  const std::vector<Body>& bodies = particles.bodies;
  const std::vector<double>& body_boxes = particles.boxes.body_boxes;
  std::vector<HandSlot>& hands = particles.hands;
  HandBodyPairs& pairs = particles.pairs;
  for (auto& entry : pairs) {
    entry.second.contacts.clear();
    entry.second.previous_faces.swap(entry.second.entry_faces);
    entry.second.entry_faces.clear();
    entry.second.lazy = false;
  }
  std::vector<uint32_t>& near_bodies = particles.scratch.near_bodies;
  std::vector<ParticleContact>& found = particles.scratch.contacts;  // swapped into the pairs: buffers are reused
  std::vector<std::vector<ParticleContact>> per_body;  // BulletObjects: all bodies of one hand at once
  std::vector<std::pair<int, int>>& ranges = particles.scratch.ranges;
  const bool bullet = def.particle_contacts == WorldDef::ParticleContacts::BulletObjects;
  int tested = 0, candidates = 0;
  for (uint32_t hi = 0; hi < hands.size(); ++hi) {
    HandSlot& h = hands[hi];
    if (!h.alive || !h.state.tracked) continue;
    // The hold path first; a still pair whose witness let go is skinned in reach (as pose_hands would have) and
    // takes the full pass below.
    bool reskin = false;
    for (auto it = pairs.lower_bound({hi, 0}); it != pairs.end() && it->first.first == hi; ++it) {
      if (!it->second.still) continue;
      if (particles.hold_by_witness(hi, it->first.second, it->second, dt)) {
        ++tested;
        candidates += 2;
      } else {
        it->second.still = false;
        reskin = true;
      }
    }
    if (reskin) particles.skin_particles_in_reach(h);
    // A hand far from every body (pose_hands) has no group within reach and cannot touch anything.
    if (!bullet && !def.paper_pipeline && h.reach_groups_only && h.reach_groups.empty()) continue;
    const double radius = h.model->particle_radius;
    if (bullet || def.paper_pipeline) particles.refresh_particles(h, false);
    if (bullet) collide_bullet_particles(particles, body_version, hi, per_body);
    // The broadphase (the widest margin); the paper pipeline tests every body.
    if (def.paper_pipeline) {
      near_bodies.clear();
      for (uint32_t bi = 0; bi < bodies.size(); ++bi) near_bodies.push_back(bi);
    } else {
      particles.boxes.bodies_near(h.state.bounds_lo, h.state.bounds_hi, def.grasp.release_distance, &near_bodies);
    }
    for (uint32_t bi : near_bodies) {
      const Vec3 lo = Eigen::Map<const Vec3>(&body_boxes[6 * bi]), hi_b = Eigen::Map<const Vec3>(&body_boxes[6 * bi + 3]);
      const Body& b = bodies[bi];
      if (!b.alive) continue;
      // A held object is no longer penetrated; count particles within release_distance as holding it.
      const bool held = b.held_by(hi);
      const double margin = held ? def.grasp.release_distance : 0.0;
      if (held) {
        auto lazy = pairs.find({hi, bi});
        if (lazy != pairs.end() && lazy->second.lazy) continue;  // held still: the witness pass answered
      }
      if (!def.paper_pipeline &&
          !bounds_overlap(h.state.bounds_lo - Vec3::Constant(margin), h.state.bounds_hi + Vec3::Constant(margin),
                          lo, hi_b))
        continue;
      ++tested;
      found.clear();
      if (bullet) {
        // The Bullet spheres carry the release margin for every body; unheld bodies need real contact.
        for (ParticleContact c : per_body[bi]) {
          c.depth -= def.grasp.release_distance;
          if (c.depth > -margin) found.push_back(c);
        }
        std::stable_sort(found.begin(), found.end(),
                         [](const ParticleContact& a, const ParticleContact& b) { return a.particle < b.particle; });
      } else {
        // The groups within reach of this body were skinned in pose_hands (skin_particles_in_reach); the
        // ranges below are those groups only.
        if (def.paper_pipeline) ranges.assign(1, {0, int(h.state.tracked_positions.cols())});
        else near_particle_ranges(h, radius + margin, lo, hi_b, ranges);
        for (const auto& r : ranges) candidates += r.second - r.first;
        collide_particle_ranges(h.state.tracked_positions, ranges, radius + margin, b.prepared, b.pose, found);
        for (ParticleContact& c : found) c.depth -= margin;  // true depth; held contacts may be slightly < 0
      }
      auto key = std::make_pair(hi, bi);
      auto it = pairs.find(key);
      if (found.empty() && it == pairs.end()) continue;
      if (it == pairs.end()) {
        it = pairs.emplace(key, HandBodyPair(def.grasp)).first;
        // A first touch in the hand's first tracked frame with a centre already inside (HandBodyPair::appeared_inside).
        it->second.appeared_inside =
            def.grasp.closing_distance > 0 && !h.history.has_velocity() &&
            std::any_of(found.begin(), found.end(), [&](const ParticleContact& c) { return c.depth > radius; });
      }
      keep_entry_faces(h.state.tracked_positions, radius, b.prepared, b.pose, {b.linear, b.angular}, motion_of(def, h), dt, it->second.previous_faces,
                       it->second.entry_faces, found);
      it->second.contacts.swap(found);
      // A held pair's full pass is the anchor of the hold path's next steps.
      // (A copy: the bones are taken into the body's frame only when holds_still compares them.)
      if (held && particles.hold_path && !bullet && !def.paper_pipeline) {
        it->second.anchor.assign(h.state.bones.begin(), h.state.bones.end());
        it->second.anchor_pose = b.pose;
      } else {
        it->second.anchor.clear();
      }
      it->second.anchor_in_body.clear();
    }
  }
  if (tested == 0) return stage_skipped(SkipReason::NoHandNearBody);
  return stage_work(tested, candidates);
}

// The particle index ranges whose group box, grown by the contact reach, overlaps a body's world box: the
// particles of the other groups are farther than `reach` from the body's bounds, so they cannot touch it.
void near_particle_ranges(const HandSlot& h, double reach, const Vec3& body_lo, const Vec3& body_hi,
                          std::vector<std::pair<int, int>>& ranges) {
  ranges.clear();
  // A little slack over the reach, so a centre exactly at the reach is never dropped by rounding.
  const Vec3 grow = Vec3::Constant(reach * (1 + 1e-9) + 1e-12);
  const std::vector<SkinGroup>& groups = h.model->particle_skin.groups;
  auto consider = [&](size_t g) {
    const Vec3 lo = Eigen::Map<const Vec3>(&h.group_bounds[6 * g]) - grow;
    const Vec3 hi = Eigen::Map<const Vec3>(&h.group_bounds[6 * g + 3]) + grow;
    if (!bounds_overlap(lo, hi, body_lo, body_hi)) return;
    if (!ranges.empty() && ranges.back().second == groups[g].begin) ranges.back().second = groups[g].end;
    else ranges.push_back({groups[g].begin, groups[g].end});
  };
  // Only the groups skinned within reach of a body can touch one (the others have empty boxes).
  if (h.reach_groups_only)
    for (uint32_t g : h.reach_groups) consider(g);
  else
    for (size_t g = 0; g < groups.size(); ++g) consider(g);
}

// The paper's narrow phase: the hand's particles as Bullet sphere objects (radius + release margin) in a
// collision world holding every body; rebuilt whenever bodies were added or removed.
namespace {
void collide_bullet_particles(HandParticles& particles, uint64_t body_version, uint32_t hi,
                              std::vector<std::vector<ParticleContact>>& per_body) {
  const WorldDef& def = particles.def;
  const std::vector<Body>& bodies = particles.bodies;
  HandSlot& h = particles.hands[hi];
  if (!h.bullet_particles || h.bullet_version != body_version) {
    h.bullet_particles = std::make_unique<BulletParticleCollider>(
        h.model->particle_count(), h.model->particle_radius + def.grasp.release_distance);
    h.bullet_bodies.clear();
    for (uint32_t bi = 0; bi < bodies.size(); ++bi)
      if (bodies[bi].alive) {
        h.bullet_particles->add_body(bodies[bi].shape, bodies[bi].pose);
        h.bullet_bodies.push_back(bi);
      }
    h.bullet_version = body_version;
  }
  for (size_t k = 0; k < h.bullet_bodies.size(); ++k)
    h.bullet_particles->set_body_pose(int(k), bodies[h.bullet_bodies[k]].pose);
  std::vector<std::vector<ParticleContact>> by_collider;
  h.bullet_particles->collide(h.state.tracked_positions, by_collider);
  per_body.assign(bodies.size(), {});
  for (size_t k = 0; k < h.bullet_bodies.size() && k < by_collider.size(); ++k)
    per_body[h.bullet_bodies[k]] = std::move(by_collider[k]);
}

}  // namespace

}  // namespace handsim
