#include "handsim/shape.h"

#include "validate.h"

namespace handsim {

void validate_shape(const ShapeDef& s, const std::string& arg) {
  auto check_points = [&] {
    for (size_t i = 0; i < s.points.size(); ++i) validate::point(s.points[i], arg + ".points[" + std::to_string(i) + "]");
  };
  switch (s.type) {
    case ShapeType::Box:
      validate::size(s.half_extents, arg + ".half_extents");
      return;
    case ShapeType::Sphere:
      validate::size(s.radius, arg + ".radius");
      return;
    case ShapeType::Capsule:
      validate::size(s.radius, arg + ".radius");
      validate::in_range(s.half_height, 0, validate::kMaxCoordinate, arg + ".half_height", "m");
      return;
    case ShapeType::ConvexHull:
      if (s.points.size() < 4) validate::fail(arg + ".points", "a convex hull needs at least 4 points");
      check_points();
      return;
    case ShapeType::TriangleMesh:
      if (s.points.size() < 3) validate::fail(arg + ".points", "a triangle mesh needs at least 3 vertices");
      if (s.indices.empty() || s.indices.size() % 3 != 0)
        validate::fail(arg + ".indices", "must hold three vertex indices per triangle");
      check_points();
      for (int i : s.indices)
        if (i < 0 || size_t(i) >= s.points.size())
          validate::fail(arg + ".indices", "index " + std::to_string(i) + " is out of range");
      return;
  }
  validate::fail(arg + ".type", "unknown shape type " + std::to_string(int(s.type)));
}

void shape_local_bounds(const ShapeDef& s, Vec3& lo, Vec3& hi) {
  switch (s.type) {
    case ShapeType::Box:
      hi = s.half_extents;
      break;
    case ShapeType::Sphere:
      hi = Vec3::Constant(s.radius);
      break;
    case ShapeType::Capsule:
      hi = Vec3(s.radius, s.radius + s.half_height, s.radius);
      break;
    case ShapeType::ConvexHull:
    case ShapeType::TriangleMesh:
      lo = hi = s.points.front();
      for (const Vec3& p : s.points) {
        lo = lo.cwiseMin(p);
        hi = hi.cwiseMax(p);
      }
      return;
  }
  lo = -hi;
}

// Principal moments of inertia per kg in the body frame. Hulls and meshes use their bounding box: the
// joint dynamics only needs the inertia to within a few percent for a plausible swing.
Vec3 shape_unit_inertia(const ShapeDef& s) {
  switch (s.type) {
    case ShapeType::Sphere:
      return Vec3::Constant(0.4 * s.radius * s.radius);
    case ShapeType::Capsule: {
      // A cylinder of the capsule's full length: within ~10% of the exact capsule.
      const double r2 = s.radius * s.radius, length = 2 * (s.half_height + s.radius);
      const double across = (3 * r2 + length * length) / 12.0;
      return Vec3(across, 0.5 * r2, across);
    }
    default: {
      Vec3 lo, hi;
      shape_local_bounds(s, lo, hi);
      const Vec3 e2 = (0.5 * (hi - lo)).array().square();
      return Vec3(e2.y() + e2.z(), e2.x() + e2.z(), e2.x() + e2.y()) / 3.0;
    }
  }
}

}  // namespace handsim
