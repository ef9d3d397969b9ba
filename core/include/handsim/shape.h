// Collision shapes of bodies, in the body's local frame.
#pragma once

#include "handsim/types.h"

#include <vector>

namespace handsim {

HANDSIM_DECLARE_ENUM(ShapeType, HANDSIM_ENUM_SHAPE_TYPE);

struct ShapeDef {
  ShapeType type = ShapeType::Box;
  Vec3 half_extents = Vec3(0.05, 0.05, 0.05);  // Box
  double radius = 0.05;                         // Sphere, Capsule
  double half_height = 0.05;                    // Capsule: half the length of its core segment, along local Y
  std::vector<Vec3> points;                     // ConvexHull: the points; TriangleMesh: the vertices
  std::vector<int> indices;                     // TriangleMesh: three vertex indices per triangle

  static ShapeDef box(const Vec3& half_extents) {
    ShapeDef s;
    s.type = ShapeType::Box;
    s.half_extents = half_extents;
    return s;
  }
  static ShapeDef sphere(double radius) {
    ShapeDef s;
    s.type = ShapeType::Sphere;
    s.radius = radius;
    return s;
  }
  static ShapeDef capsule(double radius, double half_height) {
    ShapeDef s;
    s.type = ShapeType::Capsule;
    s.radius = radius;
    s.half_height = half_height;
    return s;
  }
  static ShapeDef convex_hull(std::vector<Vec3> points) {
    ShapeDef s;
    s.type = ShapeType::ConvexHull;
    s.points = std::move(points);
    return s;
  }
  static ShapeDef triangle_mesh(std::vector<Vec3> vertices, std::vector<int> indices) {
    ShapeDef s;
    s.type = ShapeType::TriangleMesh;
    s.points = std::move(vertices);
    s.indices = std::move(indices);
    return s;
  }
};

// Throws handsim::Error naming `argument` (e.g. "body.shape.half_extents") when the shape is unusable.
void validate_shape(const ShapeDef& shape, const std::string& argument);

// Local-frame axis-aligned bounds of the shape.
void shape_local_bounds(const ShapeDef& shape, Vec3& lo, Vec3& hi);
// Principal moments of inertia per kg about the body origin, body frame (boxes, spheres exact; capsules as
// a cylinder of their full length; hulls and meshes as their bounding box).
Vec3 shape_unit_inertia(const ShapeDef& shape);

}  // namespace handsim
