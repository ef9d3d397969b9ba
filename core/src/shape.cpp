#include "handsim/shape.h"

#include "validate.h"

namespace handsim {

void validate_shape(const ShapeDef& s, const std::string& arg) {
  switch (s.type) {
    case ShapeType::Box:
      validate::positive(s.half_extents, arg + ".half_extents");
      return;
    case ShapeType::Sphere:
      validate::positive(s.radius, arg + ".radius");
      return;
    case ShapeType::Capsule:
      validate::positive(s.radius, arg + ".radius");
      validate::non_negative(s.half_height, arg + ".half_height");
      return;
    case ShapeType::ConvexHull:
      if (s.points.size() < 4) validate::fail(arg + ".points", "a convex hull needs at least 4 points");
      for (const Vec3& p : s.points) validate::finite(p, arg + ".points");
      return;
    case ShapeType::TriangleMesh:
      if (s.points.size() < 3) validate::fail(arg + ".points", "a triangle mesh needs at least 3 vertices");
      if (s.indices.empty() || s.indices.size() % 3 != 0)
        validate::fail(arg + ".indices", "must hold three vertex indices per triangle");
      for (const Vec3& p : s.points) validate::finite(p, arg + ".points");
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

}  // namespace handsim
