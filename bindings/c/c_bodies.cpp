// C ABI: bodies (shapes, poses, velocities, grasps, contacts).
#include "c_api.h"

namespace handsim::capi {

// The field map and the shape's arrays (hull points, mesh vertices and indices), read during the call.
static BodyDef to_cpp(const handsim_body_def& b) {
  BodyDef d = from_c<BodyDef>(b);
  const handsim_shape& s = b.shape;
  if (s.type == HANDSIM_SHAPE_CONVEX_HULL || s.type == HANDSIM_SHAPE_TRIANGLE_MESH) {
    input_array(s.points, s.point_count, "body.shape.points", "body.shape.point_count");
    d.shape.points.reserve(size_t(s.point_count));
    for (int32_t i = 0; i < s.point_count; ++i) d.shape.points.push_back(capi::to_cpp(s.points[i]));
  }
  if (s.type == HANDSIM_SHAPE_TRIANGLE_MESH) {
    input_array(s.indices, s.index_count, "body.shape.indices", "body.shape.index_count");
    d.shape.indices.assign(s.indices, s.indices + s.index_count);
  }
  return d;
}

}  // namespace handsim::capi

using namespace handsim;
using namespace handsim::capi;

extern "C" {

HANDSIM_API int HANDSIM_CALL handsim_body_def_default(handsim_body_def* out_def) {
  return guarded([&] { deref(out_def, "out_def") = as_c<handsim_body_def>(BodyDef{}); });
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
  return remove_id<BodyId>(world, body, &World::remove_body);
}

HANDSIM_API int HANDSIM_CALL handsim_contains_body(const handsim_world* world, handsim_body_id body,
                                                   int32_t* out_alive) {
  return contains_id<BodyId>(world, body, out_alive);
}

HANDSIM_API int HANDSIM_CALL handsim_bodies(const handsim_world* world, handsim_body_id* out_bodies,
                                            int32_t capacity, int32_t* count) {
  return list_ids<BodyId>(world, &World::bodies, out_bodies, capacity, count, "out_bodies");
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
    out = as_c<handsim_grasp_info>(w.body_grasp(body_id(body)));
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
