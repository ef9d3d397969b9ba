// C ABI: bodies (shapes, poses, velocities, grasps, contacts).
#include "c_api.h"

namespace handsim::capi {

static ShapeDef to_cpp(const handsim_shape& s) {
  ShapeDef d;
  d.type = ShapeType(s.type);
  d.half_extents = capi::to_cpp(s.half_extents);
  d.radius = s.radius;
  d.half_height = s.half_height;
  if (s.type == HANDSIM_SHAPE_CONVEX_HULL || s.type == HANDSIM_SHAPE_TRIANGLE_MESH) {
    input_array(s.points, s.point_count, "body.shape.points", "body.shape.point_count");
    d.points.reserve(size_t(s.point_count));
    for (int32_t i = 0; i < s.point_count; ++i) d.points.push_back(capi::to_cpp(s.points[i]));
  }
  if (s.type == HANDSIM_SHAPE_TRIANGLE_MESH) {
    input_array(s.indices, s.index_count, "body.shape.indices", "body.shape.index_count");
    d.indices.assign(s.indices, s.indices + s.index_count);
  }
  return d;
}

static BodyDef to_cpp(const handsim_body_def& b) {
  BodyDef d;
  d.shape = to_cpp(b.shape);
  d.mass = b.mass;
  d.pose = capi::to_cpp(b.pose);
  d.linear_velocity = capi::to_cpp(b.linear_velocity);
  d.angular_velocity = capi::to_cpp(b.angular_velocity);
  d.friction = b.friction;
  d.restitution = b.restitution;
  d.kinematic = b.kinematic != 0;
  return d;
}

static handsim_body_def to_c(const BodyDef& d) {
  handsim_body_def b{};
  b.shape.type = int32_t(d.shape.type);
  b.shape.half_extents = capi::to_c(d.shape.half_extents);
  b.shape.radius = d.shape.radius;
  b.shape.half_height = d.shape.half_height;
  b.mass = d.mass;
  b.pose = capi::to_c(d.pose);
  b.linear_velocity = capi::to_c(d.linear_velocity);
  b.angular_velocity = capi::to_c(d.angular_velocity);
  b.friction = d.friction;
  b.restitution = d.restitution;
  b.kinematic = d.kinematic;
  return b;
}

}  // namespace handsim::capi

using namespace handsim;
using namespace handsim::capi;

extern "C" {

HANDSIM_API int HANDSIM_CALL handsim_body_def_default(handsim_body_def* out_def) {
  return guarded([&] { deref(out_def, "out_def") = capi::to_c(BodyDef{}); });
}

HANDSIM_API int HANDSIM_CALL handsim_add_body(handsim_world* world, const handsim_body_def* body,
                                              handsim_body_id* out_body) {
  return guarded([&] {
    World& w = checked(world).world;
    const BodyDef def = capi::to_cpp(deref(body, "body"));
    handsim_body_id& out = deref(out_body, "out_body");
    out = w.add_body(def).packed();
  });
}

HANDSIM_API int HANDSIM_CALL handsim_remove_body(handsim_world* world, handsim_body_id body) {
  return guarded([&] { checked(world).world.remove_body(body_id(body)); });
}

HANDSIM_API int HANDSIM_CALL handsim_contains_body(const handsim_world* world, handsim_body_id body,
                                                   int32_t* out_alive) {
  return guarded([&] {
    const World& w = checked(world).world;
    deref(out_alive, "out_alive") = w.contains(body_id(body));
  });
}

HANDSIM_API int HANDSIM_CALL handsim_bodies(const handsim_world* world, handsim_body_id* out_bodies,
                                            int32_t capacity, int32_t* count) {
  return guarded([&] {
    copy_ids(checked(world).world.bodies(), out_bodies, capacity, count, "out_bodies");
  });
}

HANDSIM_API int HANDSIM_CALL handsim_get_body_info(const handsim_world* world, handsim_body_id body,
                                               handsim_body_info* out_info) {
  return guarded([&] {
    const World& w = checked(world).world;
    handsim_body_info& out = deref(out_info, "out_info");
    const BodyId id = body_id(body);
    const ShapeDef& shape = w.body_shape(id);
    out = {int32_t(w.body_motion(id)), int32_t(shape.type), w.body_mass(id), capi::to_c(shape.half_extents),
           shape.radius, shape.half_height, int32_t(shape.points.size()), int32_t(shape.indices.size())};
  });
}

HANDSIM_API int HANDSIM_CALL handsim_body_pose(const handsim_world* world, handsim_body_id body,
                                               handsim_pose* out_pose) {
  return guarded([&] {
    const World& w = checked(world).world;
    handsim_pose& out = deref(out_pose, "out_pose");
    out = capi::to_c(w.body_pose(body_id(body)));
  });
}

HANDSIM_API int HANDSIM_CALL handsim_body_poses(const handsim_world* world, const handsim_body_id* bodies,
                                                int32_t count, handsim_pose* out_poses) {
  return guarded([&] {
    const World& w = checked(world).world;
    input_array(bodies, count, "bodies", "count");
    input_array(out_poses, count, "out_poses", "count");
    for (int32_t i = 0; i < count; ++i)  // every id is checked before anything is written
      if (!w.contains(body_id(bodies[i])))
        validate::fail("bodies[" + std::to_string(i) + "]", "names no live body (removed, or from another world)",
                       Status::StaleId);
    for (int32_t i = 0; i < count; ++i) out_poses[i] = capi::to_c(w.body_pose(body_id(bodies[i])));
  });
}

HANDSIM_API int HANDSIM_CALL handsim_set_body_pose(handsim_world* world, handsim_body_id body,
                                                   const handsim_pose* pose) {
  return guarded([&] {
    World& w = checked(world).world;
    w.set_body_pose(body_id(body), capi::to_cpp(deref(pose, "pose")));
  });
}

HANDSIM_API int HANDSIM_CALL handsim_body_velocity(const handsim_world* world, handsim_body_id body,
                                                   handsim_vec3* out_linear, handsim_vec3* out_angular) {
  return guarded([&] {
    const World& w = checked(world).world;
    const BodyId id = body_id(body);
    const Vec3 linear = w.body_linear_velocity(id), angular = w.body_angular_velocity(id);
    if (out_linear) *out_linear = capi::to_c(linear);
    if (out_angular) *out_angular = capi::to_c(angular);
  });
}

HANDSIM_API int HANDSIM_CALL handsim_set_body_velocity(handsim_world* world, handsim_body_id body,
                                                       const handsim_vec3* linear, const handsim_vec3* angular) {
  return guarded([&] {
    World& w = checked(world).world;
    w.set_body_velocity(body_id(body), capi::to_cpp(deref(linear, "linear")), capi::to_cpp(deref(angular, "angular")));
  });
}

HANDSIM_API int HANDSIM_CALL handsim_body_grasp(const handsim_world* world, handsim_body_id body,
                                                handsim_grasp_info* out_grasp) {
  return guarded([&] {
    const World& w = checked(world).world;
    handsim_grasp_info& out = deref(out_grasp, "out_grasp");
    const GraspInfo g = w.body_grasp(body_id(body));
    out = {g.grasped, 0, g.primary.packed(), g.secondary.packed(), capi::to_c(g.primary_relative)};
  });
}

HANDSIM_API int HANDSIM_CALL handsim_body_contact_count(const handsim_world* world, handsim_body_id body,
                                                        handsim_hand_id hand, int32_t* out_count) {
  return guarded([&] {
    const World& w = checked(world).world;
    int32_t& out = deref(out_count, "out_count");
    out = w.body_contact_count(body_id(body), hand_id(hand));
  });
}

}  // extern "C"
