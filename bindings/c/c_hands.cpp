// C ABI: hands (frames in, particles and render vertices out), synthetic hand frames and the jewelry box scene.
#include "c_api.h"

namespace handsim::capi {

void to_cpp(const handsim_hand_frame& frame, const std::string& argument, HandFrame& out) {
  if (frame.joint_count != kHandJointCount)
    validate::fail(argument + ".joint_count", "must be " + std::to_string(kHandJointCount) +
                                                  " (HANDSIM_HAND_JOINT_COUNT), got " +
                                                  std::to_string(frame.joint_count));
  if (!frame.joints) validate::fail(argument + ".joints", "must not be null");
  out.handedness = Handedness(frame.handedness);
  for (int j = 0; j < kHandJointCount; ++j) out.joints[size_t(j)] = from_c<JointPose>(frame.joints[j]);
}

void write_joints(const HandFrame& frame, handsim_joint_pose* out_joints, int32_t capacity) {
  deref(out_joints, "out_joints");
  if (capacity < kHandJointCount)
    validate::fail("out_joints", "capacity " + std::to_string(capacity) + " is too small, needs " +
                                     std::to_string(kHandJointCount));
  for (int j = 0; j < kHandJointCount; ++j) out_joints[j] = as_c<handsim_joint_pose>(frame.joints[size_t(j)]);
}

static SkinnedMesh to_cpp(const handsim_skinned_mesh& m) {
  input_array(m.positions, m.vertex_count, "mesh.positions", "mesh.vertex_count");
  input_array(m.bones, m.vertex_count, "mesh.bones", "mesh.vertex_count");
  input_array(m.weights, m.vertex_count, "mesh.weights", "mesh.vertex_count");
  input_array(m.triangles, m.triangle_index_count, "mesh.triangles", "mesh.triangle_index_count");
  SkinnedMesh s;
  const Eigen::Index n = m.vertex_count;
  s.positions.resize(3, n);
  s.bones.resize(4, n);
  s.weights.resize(4, n);
  for (Eigen::Index i = 0; i < n; ++i) {
    s.positions.col(i) = capi::to_cpp(m.positions[i]);
    for (int k = 0; k < 4; ++k) {
      s.bones(k, i) = m.bones[4 * i + k];
      s.weights(k, i) = m.weights[4 * i + k];
    }
  }
  s.triangles.assign(m.triangles, m.triangles + m.triangle_index_count);
  return s;
}

// The hand model and state a query reads, after the world and id checks.
static const HandModel& model_of(const handsim_world* world, handsim_hand_id hand) {
  return checked(world).world.hand_model(hand_id(hand));
}

// Render vertices as x, y, z values of T; a size query does not skin.
template <class T>
static int render_vertices(handsim_world* world, handsim_hand_id hand, T* out, int32_t capacity, int32_t* count,
                    const char* out_name) {
  return guarded([&] {
    const int32_t n = model_of(world, hand).vertex_count();
    if (output_buffer(out, capacity, count, size_t(n), out_name))
      write_points(checked(world).world.hand_render_vertices(hand_id(hand)), out);
  });
}

}  // namespace handsim::capi

using namespace handsim;
using namespace handsim::capi;

extern "C" {

HANDSIM_API int HANDSIM_CALL handsim_hand_def_default(handsim_hand_def* out_def) {
  return guarded([&] { deref(out_def, "out_def") = as_c<handsim_hand_def>(HandDef{}); });
}

HANDSIM_API int HANDSIM_CALL handsim_hand_pose_params_default(handsim_hand_pose_params* out_params) {
  return guarded([&] { deref(out_params, "out_params") = as_c<handsim_hand_pose_params>(HandPoseParams{}); });
}

HANDSIM_API int HANDSIM_CALL handsim_jewelry_box_def_default(handsim_jewelry_box_def* out_def) {
  return guarded([&] { deref(out_def, "out_def") = as_c<handsim_jewelry_box_def>(JewelryBoxDef{}); });
}

HANDSIM_API int HANDSIM_CALL handsim_add_hand(handsim_world* world, const handsim_hand_def* def,
                                              handsim_hand_id* out_hand) {
  return guarded([&] {
    World& w = checked(world).world;
    const HandDef d = def ? from_c<HandDef>(*def) : HandDef{};
    handsim_hand_id& out = deref(out_hand, "out_hand");
    out = w.add_hand(d).packed();
  });
}

HANDSIM_API int HANDSIM_CALL handsim_add_hand_with_mesh(handsim_world* world, const handsim_hand_def* def,
                                                        const handsim_skinned_mesh* mesh,
                                                        const handsim_hand_frame* bind, handsim_hand_id* out_hand) {
  return guarded([&] {
    World& w = checked(world).world;
    const HandDef d = from_c<HandDef>(deref(def, "def"));
    const SkinnedMesh m = capi::to_cpp(deref(mesh, "mesh"));
    HandFrame b;
    capi::to_cpp(deref(bind, "bind"), "bind", b);
    handsim_hand_id& out = deref(out_hand, "out_hand");
    out = w.add_hand(d, m, b).packed();
  });
}

HANDSIM_API int HANDSIM_CALL handsim_remove_hand(handsim_world* world, handsim_hand_id hand) {
  return remove_id<HandId>(world, hand, &World::remove_hand);
}

HANDSIM_API int HANDSIM_CALL handsim_contains_hand(const handsim_world* world, handsim_hand_id hand,
                                                   int32_t* out_alive) {
  return contains_id<HandId>(world, hand, out_alive);
}

HANDSIM_API int HANDSIM_CALL handsim_hands(const handsim_world* world, handsim_hand_id* out_hands, int32_t capacity,
                                           int32_t* count) {
  return list_ids<HandId>(world, &World::hands, out_hands, capacity, count, "out_hands");
}

HANDSIM_API int HANDSIM_CALL handsim_get_hand_info(const handsim_world* world, handsim_hand_id hand,
                                               handsim_hand_info* out_info) {
  return guarded([&] {
    const World& w = checked(world).world;
    const HandModel& m = model_of(world, hand);
    handsim_hand_info& out = deref(out_info, "out_info");
    const HandId id = hand_id(hand);
    out = {int32_t(m.handedness), w.hand_tracked(id), m.particle_count(), m.vertex_count(),
           int32_t(m.mesh.triangles.size()), 0, m.particle_radius, capi::to_c(w.hand_palm_pose(id))};
  });
}

HANDSIM_API int HANDSIM_CALL handsim_hand_particles(const handsim_world* world, handsim_hand_id hand, int32_t deformed,
                                                    handsim_vec3* out_positions, int32_t capacity, int32_t* count) {
  return guarded([&] {
    const Eigen::Matrix3Xd& p = checked(world).world.hand_particles(hand_id(hand), deformed != 0);
    if (output_buffer(out_positions, capacity, count, size_t(p.cols()), "out_positions"))
      write_points(p, &out_positions->x);
  });
}

HANDSIM_API int HANDSIM_CALL handsim_hand_render_vertices(handsim_world* world, handsim_hand_id hand,
                                                          handsim_vec3* out_vertices, int32_t capacity,
                                                          int32_t* count) {
  return render_vertices(world, hand, out_vertices ? &out_vertices->x : nullptr, capacity, count, "out_vertices");
}

HANDSIM_API int HANDSIM_CALL handsim_hand_render_vertices_f32(handsim_world* world, handsim_hand_id hand,
                                                              float* out_xyz, int32_t capacity, int32_t* count) {
  return render_vertices(world, hand, out_xyz, capacity, count, "out_xyz");
}

HANDSIM_API int HANDSIM_CALL handsim_hand_triangles(const handsim_world* world, handsim_hand_id hand,
                                                    int32_t* out_indices, int32_t capacity, int32_t* count) {
  return guarded([&] { copy_ints(model_of(world, hand).mesh.triangles, out_indices, capacity, count, "out_indices"); });
}

HANDSIM_API int HANDSIM_CALL handsim_hand_source_vertices(const handsim_world* world, handsim_hand_id hand,
                                                          int32_t* out_indices, int32_t capacity, int32_t* count) {
  return guarded([&] { copy_ints(model_of(world, hand).source_vertex, out_indices, capacity, count, "out_indices"); });
}

HANDSIM_API int HANDSIM_CALL handsim_make_hand_frame(int32_t handedness, const handsim_pose* palm_pose,
                                                     const handsim_hand_pose_params* params,
                                                     handsim_joint_pose* out_joints, int32_t capacity) {
  return guarded([&] {
    const Pose palm = capi::to_cpp(deref(palm_pose, "palm_pose"));
    const HandPoseParams p = params ? from_c<HandPoseParams>(*params) : HandPoseParams{};
    HandFrame frame;
    try {
      frame = make_hand_frame(Handedness(handedness), palm, p);
    } catch (const Error& e) {
      static const char* const kCurl[] = {"thumb", "index", "middle", "ring", "little"};
      for (int i = 0; i < 5; ++i)
        if (e.argument() == "params.curl[" + std::to_string(i) + "]")
          rethrow_renamed(e, e.argument(), std::string("params.curl_") + kCurl[i]);
      throw;
    }
    write_joints(frame, out_joints, capacity);
  });
}

HANDSIM_API int HANDSIM_CALL handsim_bind_frame(int32_t handedness, double scale, handsim_joint_pose* out_joints,
                                                int32_t capacity) {
  return guarded([&] {
    if (handedness != HANDSIM_LEFT && handedness != HANDSIM_RIGHT)
      validate::fail("handedness", "must be HANDSIM_LEFT (0) or HANDSIM_RIGHT (1), got " + std::to_string(handedness));
    validate::positive(scale, "scale");
    write_joints(bind_frame(Handedness(handedness), scale), out_joints, capacity);
  });
}

HANDSIM_API int HANDSIM_CALL handsim_lid_pinch_shape(handsim_hand_pose_params* out_params) {
  return guarded([&] { deref(out_params, "out_params") = as_c<handsim_hand_pose_params>(lid_pinch_shape()); });
}

HANDSIM_API int HANDSIM_CALL handsim_open_grip(const handsim_hand_pose_params* grip, double openness,
                                               handsim_hand_pose_params* out_params) {
  return guarded([&] {
    const HandPoseParams g = from_c<HandPoseParams>(deref(grip, "grip"));
    deref(out_params, "out_params") = as_c<handsim_hand_pose_params>(open_grip(g, openness));
  });
}

HANDSIM_API int HANDSIM_CALL handsim_closing_grip(const handsim_hand_pose_params* grip, double t, double duration,
                                                  handsim_hand_pose_params* out_params) {
  return guarded([&] {
    const HandPoseParams g = from_c<HandPoseParams>(deref(grip, "grip"));
    deref(out_params, "out_params") = as_c<handsim_hand_pose_params>(closing_grip(g, t, duration));
  });
}

HANDSIM_API int HANDSIM_CALL handsim_build_jewelry_box(handsim_world* world, const handsim_jewelry_box_def* jewelry_box,
                                                       handsim_jewelry_box* out_box) {
  return guarded([&] {
    World& w = checked(world).world;
    const JewelryBoxDef d = jewelry_box ? from_c<JewelryBoxDef>(*jewelry_box) : JewelryBoxDef{};
    handsim_jewelry_box& out = deref(out_box, "out_box");
    const JewelryBox box = build_jewelry_box(w, d);
    out = as_c<handsim_jewelry_box>(box);
  });
}

HANDSIM_API int HANDSIM_CALL handsim_jewelry_box_lid_pinch_palm(const handsim_world* world,
                                                                const handsim_jewelry_box* box, int32_t handedness,
                                                                double angle, double lift, handsim_pose* out_palm) {
  return guarded([&] {
    const World& w = checked(world).world;
    const JewelryBox b = from_c<JewelryBox>(deref(box, "box"));
    handsim_pose& out = deref(out_palm, "out_palm");
    if (handedness != HANDSIM_LEFT && handedness != HANDSIM_RIGHT)
      validate::fail("handedness", "must be HANDSIM_LEFT (0) or HANDSIM_RIGHT (1), got " + std::to_string(handedness));
    validate::finite(angle, "angle");
    validate::finite(lift, "lift");
    out = capi::to_c(b.lid_pinch_palm(w, Handedness(handedness), angle, lift));
  });
}

HANDSIM_API int HANDSIM_CALL handsim_jewelry_box_points(const handsim_world* world, const handsim_jewelry_box* box,
                                                        handsim_vec3* out_lid_front, handsim_vec3* out_hinge_pivot,
                                                        handsim_vec3* out_hinge_axis) {
  return guarded([&] {
    const World& w = checked(world).world;
    const JewelryBox b = from_c<JewelryBox>(deref(box, "box"));
    const Vec3 front = b.lid_front(w), pivot = b.hinge_pivot(w), axis = b.hinge_axis(w);
    if (out_lid_front) *out_lid_front = capi::to_c(front);
    if (out_hinge_pivot) *out_hinge_pivot = capi::to_c(pivot);
    if (out_hinge_axis) *out_hinge_axis = capi::to_c(axis);
  });
}

}  // extern "C"
