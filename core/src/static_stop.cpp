// A held body stops at static geometry (issue 20 item 3; docs/grasp.md, "Static geometry stops a held body").
// The attach stage puts a held body at palm * T_rel of its primary hand. A hand that goes on into a table (the
// tracked hand meets no table) would drive the body through it; instead the body is translated out of the ground
// and of static bodies (mass 0: tables, fixed bases) along their surface normals only, so it stays on the surface
// and slides along it with the hand's tangential motion. Only the hand's skin lies between the two: while the hand
// is at most GraspSettings::slip_distance past the stopped body, T_rel is kept (lifting again brings the body back
// to where the hand held it); further, the fingers slip along the body (T_rel is re-taken so that the hand stays
// slip_distance past), until they slide off it and eq. 3 ends the grasp.
#include "world_impl.h"

#include <algorithm>
#include <limits>

namespace handsim {
namespace {

// Penetration a held body is left in: 0.5 mm. A body Bullet keeps at rest on the ground sinks in by a fraction of a
// millimetre (its contact solver corrects penetration over substeps rather than all at once), so a body grasped
// where it rests starts that deep; it is not pushed out by this, which keeps its pose (and the golden state hash)
// as before when nothing held presses on static geometry. A quarter of the 2 mm bound.
constexpr double kStaticSlop = 0.0005;
// Re-queries of the geometry after a push (a push out of one surface can go into another: a corner of the ground
// and a wall) and projection passes over the stops of one query. A body wedged between surfaces closer than its
// own size cannot get out of all of them; it keeps the best compromise the passes reach.
constexpr int kQueries = 3;
constexpr int kPasses = 8;
// How near a static surface a point of a body must be for the surface to bear it (support_contacts): 1 mm. Bullet
// keeps a resting body a fraction of a millimetre in or out of its support (its contact solver corrects penetration
// over substeps, and the collision margin rounds a box's corners), so a body at rest on a table lies well within it;
// a body lifted clear by more than this is in the air. A point this near a surface but not on it only stops the
// body from being pushed into the surface by that much, which the surface would do a millimetre later anyway.
constexpr double kSupportGap = 0.001;
// What the bounds below allow for the rounding of world boxes and shape points: 1 nm, ~1e7 times the rounding of
// coordinates of metres (~1e-16 m) and 1/500,000 of the slop.
constexpr double kRounding = 1e-9;

// Points that stand for a shape, with the radius of their spheres: a box's corners, edge midpoints and face
// centres (a table edge passing under the middle of a held box's face meets a face centre); a sphere's centre;
// a capsule's two cap centres and its middle; the points of a hull or mesh.
void shape_points(const PreparedShape& ps, const Pose& pose, Eigen::Matrix3Xd& out, double& radius) {
  const ShapeDef& s = ps.shape;
  const std::vector<Vec3>& listed = s.type == ShapeType::ConvexHull ? ps.hull_vertices : s.points;
  const Eigen::Index n = s.type == ShapeType::Box       ? 26
                         : s.type == ShapeType::Sphere  ? 1
                         : s.type == ShapeType::Capsule ? 3
                                                        : Eigen::Index(listed.size());
  out.resize(3, n);  // reallocates only when the count changes
  radius = s.type == ShapeType::Sphere || s.type == ShapeType::Capsule ? s.radius : 0.0;
  Eigen::Index k = 0;
  auto put = [&](const Vec3& local) { out.col(k++) = pose.transform(local); };
  switch (s.type) {
    case ShapeType::Box:
      for (int x = -1; x <= 1; ++x)
        for (int y = -1; y <= 1; ++y)
          for (int z = -1; z <= 1; ++z)
            if (x || y || z) put(s.half_extents.cwiseProduct(Vec3(x, y, z)));
      break;
    case ShapeType::Sphere: put(Vec3::Zero()); break;
    case ShapeType::Capsule:
      for (double y : {-s.half_height, 0.0, s.half_height}) put(Vec3(0, y, 0));
      break;
    case ShapeType::ConvexHull:
    case ShapeType::TriangleMesh:
      for (const Vec3& p : listed) put(p);
      break;
  }
}

// The translation that satisfies every stop (normal . t >= depth - slop), by cyclic projection onto their
// half-spaces: exact for one surface, and for surfaces at right angles (floor and wall) after one pass.
Vec3 satisfy(const std::vector<StaticStop>& stops) {
  Vec3 t = Vec3::Zero();
  for (int pass = 0; pass < kPasses; ++pass) {
    bool moved = false;
    for (const StaticStop& s : stops) {
      const double short_by = s.depth - kStaticSlop - s.normal.dot(t);
      if (short_by > 0) t += short_by * s.normal, moved = true;
    }
    if (!moved) break;
  }
  return t;
}

}  // namespace

// Every way `held` at `pose` is inside static geometry: a direction to push it and how deep it is in.
void static_stops(const WorldDef& def, const std::vector<Body>& bodies, const BodyBoxes& boxes,
                  StaticStopScratch& scratch, const Body& held, const Pose& pose, std::vector<StaticStop>& out) {
  out.clear();
  Eigen::Matrix3Xd& points = scratch.points;
  double radius = 0;
  shape_points(held.prepared, pose, points, radius);
  if (def.ground)
    for (Eigen::Index i = 0; i < points.cols(); ++i) {
      const double depth = def.ground_height - (points(1, i) - radius);
      if (depth > 0) out.push_back({Vec3::UnitY(), depth});
    }
  Vec3 lo, hi;
  local_box_in_world(held.prepared.local_lo, held.prepared.local_hi, pose, lo, hi);
  boxes.bodies_near(lo, hi, 0, &scratch.near);
  std::vector<ParticleContact>& contacts = scratch.contacts;
  for (uint32_t si : scratch.near) {
    const Body& s = bodies[si];
    if (!s.alive || s.declared != BodyMotion::Static) continue;
    contacts.clear();  // the held body's points in the static body
    collide_particles(points, radius, s.prepared, s.pose, contacts);
    for (const ParticleContact& c : contacts) out.push_back({c.normal, c.depth});
    // The static body's points in the held body (a table's corner under a held box), the ones near it only: a
    // static mesh may have many.
    Eigen::Matrix3Xd& theirs = scratch.theirs;
    double their_radius = 0;
    shape_points(s.prepared, s.pose, theirs, their_radius);
    std::vector<std::pair<int, int>>& ranges = scratch.ranges;
    ranges.clear();
    for (int i = 0; i < int(theirs.cols()); ++i)
      if (((theirs.col(i).array() >= lo.array() - their_radius) && (theirs.col(i).array() <= hi.array() + their_radius)).all()) {
        if (ranges.empty() || ranges.back().second != i) ranges.push_back({i, i + 1});
        else ++ranges.back().second;
      }
    if (ranges.empty()) continue;
    contacts.clear();
    collide_particle_ranges(theirs, ranges, their_radius, held.prepared, pose, contacts);
    for (const ParticleContact& c : contacts) out.push_back({-c.normal, c.depth});
  }
}

// Whether `held` at `pose` may lie deeper than the slop in static geometry: its world box, which holds its shape
// points with their spheres, reaches more than the slop below the ground's surface or overlaps a static body's box.
// Where it does neither every stop is within the slop, which satisfy leaves alone, so the push is zero without
// making the shape points (a body carried in the air, or resting on the ground within the slop).
bool may_meet_static(const WorldDef& def, const std::vector<Body>& bodies, const BodyBoxes& boxes,
                     StaticStopScratch& scratch, const Body& held, const Pose& pose) {
  Vec3 lo, hi;
  local_box_in_world(held.prepared.local_lo, held.prepared.local_hi, pose, lo, hi);
  if (def.ground && lo.y() < def.ground_height - kStaticSlop + kRounding) return true;
  boxes.bodies_near(lo, hi, 0, &scratch.near);
  return std::any_of(scratch.near.begin(), scratch.near.end(), [&](uint32_t si) {
    return bodies[si].alive && bodies[si].declared == BodyMotion::Static;
  });
}

namespace {

// The translation that takes `held` at `pose` out of static geometry (zero when it is not in deeper than the slop).
Vec3 static_push(const WorldDef& def, const std::vector<Body>& bodies, const BodyBoxes& boxes,
                 StaticStopScratch& scratch, const Body& held, const Pose& pose) {
  std::vector<StaticStop>& stops = scratch.stops;
  Vec3 total = Vec3::Zero();
  if (!may_meet_static(def, bodies, boxes, scratch, held, pose)) return total;
  for (int q = 0; q < kQueries; ++q) {
    static_stops(def, bodies, boxes, scratch, held, {pose.position + total, pose.orientation}, stops);
    const Vec3 t = satisfy(stops);
    if (t.isZero(0)) break;
    total += t;
  }
  return total;
}

}  // namespace

namespace {

// Where `s` lies within kSupportGap of `b` (its shape's `points` and `radius` at its pose, its world box lo..hi):
// b's points in s grown by the gap, and s's own points near b in b grown by the gap (a base's front edge under a
// lid's overhanging lip, where none of the lid's points stands). Each as the point and the normal out of s.
void surfaces_near(const Body& b, const Eigen::Matrix3Xd& points, double radius, const Vec3& lo, const Vec3& hi,
                   const Body& s, StaticStopScratch& scratch, std::vector<ParticleContact>& out) {
  out.clear();
  collide_particles(points, radius + kSupportGap, s.prepared, s.pose, out);
  Eigen::Matrix3Xd& theirs = scratch.theirs;
  double their_radius = 0;
  shape_points(s.prepared, s.pose, theirs, their_radius);
  std::vector<std::pair<int, int>>& ranges = scratch.ranges;
  ranges.clear();
  const double reach = their_radius + kSupportGap;
  for (int i = 0; i < int(theirs.cols()); ++i)
    if (((theirs.col(i).array() >= lo.array() - reach) && (theirs.col(i).array() <= hi.array() + reach)).all()) {
      if (ranges.empty() || ranges.back().second != i) ranges.push_back({i, i + 1});
      else ++ranges.back().second;
    }
  if (ranges.empty()) return;
  std::vector<ParticleContact>& inside = scratch.contacts;  // s's points in b: b's normal there is out of b
  inside.clear();
  collide_particle_ranges(theirs, ranges, reach, b.prepared, b.pose, inside);
  for (ParticleContact c : inside) {
    c.normal = -c.normal;
    out.push_back(c);
  }
}

// A free body bears what rests on it as the table does when it rests itself, directly or through a stack, on
// static geometry: what is pressed down onto it passes down to the table through it. Only a body under gravity
// rests; `path` holds the bodies already asked about below the one that rests on `s` (no body bears itself).
bool bears(const WorldDef& def, const std::vector<Body>& bodies, const BodyBoxes& boxes, StaticStopScratch& scratch,
           const Body& s, std::vector<const Body*>& path);

// Whether `s` supports `b` (the ground aside), and with which of its surfaces near b (`out`): static geometry
// with all of them, a body that bears (above) with those facing up against gravity, the ones its own support
// holds against a press; a press sideways into a free body slides it.
bool supports(const WorldDef& def, const std::vector<Body>& bodies, const BodyBoxes& boxes, StaticStopScratch& scratch,
              const Body& b, const Eigen::Matrix3Xd& points, double radius, const Vec3& lo, const Vec3& hi,
              const Body& s, std::vector<const Body*>& path, std::vector<ParticleContact>& out) {
  out.clear();
  if (!s.alive || &s == &b) return false;
  const bool fixed = s.declared == BodyMotion::Static;
  if (!fixed && !bears(def, bodies, boxes, scratch, s, path)) return false;
  surfaces_near(b, points, radius, lo, hi, s, scratch, out);
  if (!fixed) {
    const Vec3 up = -def.gravity.normalized();
    out.erase(std::remove_if(out.begin(), out.end(), [&](const ParticleContact& c) { return !(c.normal.dot(up) > 0); }),
              out.end());
  }
  return !out.empty();
}

bool bears(const WorldDef& def, const std::vector<Body>& bodies, const BodyBoxes& boxes, StaticStopScratch& scratch,
           const Body& s, std::vector<const Body*>& path) {
  if (s.declared != BodyMotion::Dynamic || s.jointed() || s.grasp.grasped || !(def.gravity.squaredNorm() > 0))
    return false;
  if (std::find(path.begin(), path.end(), &s) != path.end()) return false;
  // Its own points and neighbours: the caller's scratch holds the body it asks for.
  Eigen::Matrix3Xd points;
  double radius = 0;
  shape_points(s.prepared, s.pose, points, radius);
  if (def.ground && (points.row(1).array() - radius - def.ground_height).minCoeff() < kSupportGap) return true;
  Vec3 lo, hi;
  local_box_in_world(s.prepared.local_lo, s.prepared.local_hi, s.pose, lo, hi);
  std::vector<uint32_t> near;
  boxes.bodies_near(lo, hi, kSupportGap, &near);
  std::vector<ParticleContact> surfaces;
  path.push_back(&s);
  bool rests = false;
  for (uint32_t ti : near)
    if ((rests = supports(def, bodies, boxes, scratch, s, points, radius, lo, hi, bodies[ti], path, surfaces))) break;
  path.pop_back();
  return rests;
}

}  // namespace

// Where `b` rests on its support: the ground, bodies of mass 0, and free bodies that rest on them (bears, above).
// Each of the surfaces within kSupportGap (supports, above) is a contact the support pushes along its surface
// normal, never pulls, with Bullet's combined Coulomb coefficient of the two surfaces (the product, as
// btManifoldResult combines them). A point further than that is not borne by the surface.
void support_contacts(const WorldDef& def, const std::vector<Body>& bodies, const BodyBoxes& boxes,
                      StaticStopScratch& scratch, const Body& b, std::vector<SkinContact>& out) {
  out.clear();
  Eigen::Matrix3Xd& points = scratch.points;
  double radius = 0;
  shape_points(b.prepared, b.pose, points, radius);
  constexpr double kUnbounded = std::numeric_limits<double>::infinity();
  // A support's contact as the press solver takes it: normal into the support (the solver pushes along -normal,
  // out of it), a surface that does not move, no bound on what it bears.
  auto put = [&](const Vec3& point, const Vec3& out_of_support, double friction) {
    out.push_back({point, -out_of_support, Vec3::Zero(), kUnbounded, friction});
  };
  if (def.ground)
    for (Eigen::Index i = 0; i < points.cols(); ++i) {
      const double gap = points(1, i) - radius - def.ground_height;
      if (gap < kSupportGap) put(points.col(i) - (radius + gap) * Vec3::UnitY(), Vec3::UnitY(), b.friction * def.ground_friction);
    }
  Vec3 lo, hi;
  local_box_in_world(b.prepared.local_lo, b.prepared.local_hi, b.pose, lo, hi);
  boxes.bodies_near(lo, hi, kSupportGap, &scratch.near);
  std::vector<const Body*>& path = scratch.path;
  path.assign(1, &b);
  std::vector<ParticleContact>& surfaces = scratch.surfaces;
  for (uint32_t si : scratch.near) {
    const Body& s = bodies[si];
    if (!supports(def, bodies, boxes, scratch, b, points, radius, lo, hi, s, path, surfaces)) continue;
    for (const ParticleContact& c : surfaces) put(c.point, c.normal, b.friction * s.friction);
  }
}

// The deepest of the child's points (at `child_pose`) in `parent` and of the parent's points in the child: both
// ways, as for the static stops, since a lid's points lie on its own corners and face centres, none of them on the
// base's front edge a lid turning down past shut meets first. The joints' stages have no scratch of their own;
// one per thread keeps the step free of allocations once grown.
double depth_in(const Body& child, const Pose& child_pose, const Body& parent) {
  thread_local StaticStopScratch scratch;
  double depth = 0;
  double radius = 0;
  shape_points(child.prepared, child_pose, scratch.points, radius);
  scratch.contacts.clear();
  collide_particles(scratch.points, radius, parent.prepared, parent.pose, scratch.contacts);
  shape_points(parent.prepared, parent.pose, scratch.theirs, radius);
  collide_particles(scratch.theirs, radius, child.prepared, child_pose, scratch.contacts);
  for (const ParticleContact& c : scratch.contacts) depth = std::max(depth, c.depth);
  return depth;
}

namespace {
bool convex_polytope(const ShapeDef& s) { return s.type == ShapeType::Box || s.type == ShapeType::ConvexHull; }

// local_box_in_world of the body's local box at its pose, made again only when the pose or the box differs in a bit
// from the last call's (Body::box_memo).
const WorldBox& world_box(const Body& b) {
  BitKey<13> key;
  key.put(b.pose.position.data(), 3).put(b.pose.orientation.coeffs().data(), 4);
  key.put(b.prepared.local_lo.data(), 3).put(b.prepared.local_hi.data(), 3);
  return b.box_memo.get(key, [&b] {
    WorldBox box;
    local_box_in_world(b.prepared.local_lo, b.prepared.local_hi, b.pose, box.lo, box.hi);
    return box;
  });
}
}  // namespace

// A box's or hull's shape points have radius 0 and lie in the shape (a box's on its surface, a hull's at its
// vertices). A point at depth d in a box or hull is at distance d from its nearest face plane, so the ball of
// radius d about it lies inside the polytope and so inside its world box; the point also lies in its own body's
// world box. So on every axis each of the two boxes reaches at least d past the near side of the other, and where
// one of them reaches less than `depth` on some axis, no point of either lies deeper than that in the other. A lid
// on its hinge at its base's top edge reaches 0 past the base's top: its frames need no collision. Other shapes
// (spheres and capsules whose points have a radius, meshes) always may.
bool may_lie_deeper(const Body& child, const Pose& child_pose, const Body& parent, double depth) {
  if (!convex_polytope(child.prepared.shape) || !convex_polytope(parent.prepared.shape)) return true;
  Vec3 clo, chi;
  local_box_in_world(child.prepared.local_lo, child.prepared.local_hi, child_pose, clo, chi);
  const WorldBox& parent_box = world_box(parent);
  const Vec3 &plo = parent_box.lo, &phi = parent_box.hi;
  const Vec3 reach = (phi - clo).cwiseMin(chi - plo);
  return reach.minCoeff() >= depth - kRounding;
}

bool stopped_by_parent(const std::vector<Body>& bodies, const Joint& j, const Pose& before, const Pose& after) {
  if (j.parent == kWorldParent) return false;
  const Body& child = bodies[j.child];
  const Body& parent = bodies[j.parent];
  auto inside = [&](const Pose& pose) {
    return may_lie_deeper(child, pose, parent, kStaticSlop) && depth_in(child, pose, parent) > kStaticSlop;
  };
  return inside(after) && !inside(before);
}

// Where the held body `b` is this frame: palm * T_rel of its primary hand, stopped by static geometry. A hand more
// than slip_distance past the stopped body has its grip slip along it: T_rel is re-taken.
Pose held_pose(const WorldDef& def, const std::vector<Body>& bodies, const BodyBoxes& boxes,
               const std::vector<HandSlot>& hands, StaticStopScratch& scratch, Body& b, Vec3* pushed) {
  const HandSlot& h = hands[b.grasp.primary.index];
  const Pose target = h.palm * b.grasp.primary_relative;
  const Vec3 t = static_push(def, bodies, boxes, scratch, b, target);
  if (pushed) *pushed = t;
  if (t.isZero(0)) return target;
  const Pose stopped{target.position + t, target.orientation};
  const double past = t.norm(), slip = def.grasp.slip_distance;
  if (past > slip)
    b.grasp.primary_relative = h.palm.inverse() * Pose{stopped.position - t * (slip / past), target.orientation};
  return stopped;
}

}  // namespace handsim
