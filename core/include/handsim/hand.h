// Hand input (the OpenXR hand skeleton) and the settings of a virtual hand.
#pragma once

#include "handsim/shape.h"
#include "handsim/types.h"

#include <array>
#include <cstdint>
#include <string>
#include <vector>

namespace handsim {

HANDSIM_DECLARE_ENUM(Handedness, HANDSIM_ENUM_HANDEDNESS);

// OpenXR XR_EXT_hand_tracking joint order. The thumb has no intermediate joint.
enum HandJoint : int {
  kPalm = 0, kWrist = 1,
  kThumbMetacarpal = 2, kThumbProximal = 3, kThumbDistal = 4, kThumbTip = 5,
  kIndexMetacarpal = 6, kIndexProximal = 7, kIndexIntermediate = 8, kIndexDistal = 9, kIndexTip = 10,
  kMiddleMetacarpal = 11, kMiddleProximal = 12, kMiddleIntermediate = 13, kMiddleDistal = 14, kMiddleTip = 15,
  kRingMetacarpal = 16, kRingProximal = 17, kRingIntermediate = 18, kRingDistal = 19, kRingTip = 20,
  kLittleMetacarpal = 21, kLittleProximal = 22, kLittleIntermediate = 23, kLittleDistal = 24, kLittleTip = 25,
};
constexpr int kHandJointCount = 26;

// One tracked joint. Orientation follows OpenXR: -Z points along the bone towards the fingertip,
// +Y points out of the back of the hand.
struct JointPose {
  Vec3 position = Vec3::Zero();
  Quat orientation = Quat::Identity();
  double radius = 0.01;
  bool valid = true;
};

// One frame of one tracked hand.
struct HandFrame {
  Handedness handedness = Handedness::Right;
  std::array<JointPose, kHandJointCount> joints{};

  // A frame drives the hand only when its palm and wrist are valid; otherwise the hand counts as
  // untracked for this frame (tracking loss), which is legal input.
  bool tracked() const { return joints[kPalm].valid && joints[kWrist].valid; }
  Pose palm_pose() const { return {joints[kPalm].position, joints[kPalm].orientation}; }
};

HANDSIM_DECLARE_ENUM(ParticleSampling, HANDSIM_ENUM_PARTICLE_SAMPLING);

struct HandDef {
  Handedness handedness = Handedness::Right;
  // The paper's 1,182 random particles. `python -m handsim.bench particles` (docs/performance_particles.md)
  // finds 3,000 the fewest whose eq. 2 fit is within tolerance of an all-vertices hand, but a hand of 3,000
  // (either sampling) fails behaviour checks that 1,182 passes (its "behaviour gate"), so the default has not
  // moved. Clamped to the mesh's vertex count.
  int particle_count = 1182;
  ParticleSampling sampling = ParticleSampling::Random;
  uint64_t seed = 1;
  double particle_radius = 0.0;              // 0: derived from the particle spacing (3.70 mm for the default)
  int render_vertices = 39000;               // resolution of the default procedural mesh (approximate)
};

// ---------------------------------------------------------------------------------------------------------
// Synthetic hand frames: the grasp tests, experiments and simulated users build their hands with these.

struct HandPoseParams {
  std::array<double, 5> curl{};   // thumb, index, middle, ring, little: 0 flat .. 1 fist
  double thumb_opposition = 0;    // 0 thumb beside the index .. 1 thumb tip pressed against the index pad (pinch)
  double spread = 0;              // 0 fingers together .. 1 spread apart (negative: squeezed together)
  double scale = 1.0;             // hand size; 1 = adult hand (palm 9 cm long, 8 cm wide, middle finger 8 cm)
};

// An adult hand in OpenXR joint order with the palm joint at `palm_pose`: fingers along the palm's -Z, back of
// the hand +Y (the palm faces -Y). Every joint is valid; each joint's -Z points along its bone towards the tip.
// Left is the mirror image of right (thumb on +X instead of -X). Throws Error on a bad pose or parameter.
HandFrame make_hand_frame(Handedness handedness, const Pose& palm_pose, const HandPoseParams& params = {});

// The flat hand at the identity palm pose: the bind pose of the procedural mesh.
HandFrame bind_frame(Handedness handedness, double scale = 1.0);

// People close their hand onto what they grasp: they reach with it open and close the grip over the last few
// tenths of a second (GraspSettings::closing_distance begins a grasp only while a hand closes), and open it
// to let go. Every synthetic scene (tests, scenes, benches, simulated users) shapes its grips through these,
// so none relies on a hand that appears already shaped round its object.
// `grip` opened by `openness`: 0 the grip itself, 1 the open hand (every curl and the thumb's opposition 0;
// spread and scale kept), each parameter linearly in between. Throws Error naming "openness" outside 0..1.
HandPoseParams open_grip(const HandPoseParams& grip, double openness);
// 0.25 s: a reach-to-grasp closes its aperture over about the last quarter second of the reach.
constexpr double kGripClosingS = 0.25;
// The grip `t` s after the hand began to close it over `duration` s, with the minimum-jerk profile of a
// reaching movement: open for t <= 0, the grip itself from t >= duration. Throws Error naming "t" (not
// finite) or "duration" (not > 0).
HandPoseParams closing_grip(const HandPoseParams& grip, double t, double duration = kGripClosingS);

// Throws Error naming e.g. "frame.joints[7].orientation" when a valid joint has a non-finite position,
// a non-unit quaternion or a negative radius. Invalid joints are ignored (NaN there is legal).
void validate_frame(const HandFrame& frame, const std::string& argument);

// ---------------------------------------------------------------------------------------------------------
// Skinned mesh (eq. 1 of the paper): v_i = sum_j w_ij B_j v_i,bind with B_j = joint_j * bind_joint_j^-1.

struct SkinnedMesh {
  Eigen::Matrix3Xd positions;               // bind-pose vertex positions
  Eigen::Matrix<int, 4, Eigen::Dynamic> bones;  // up to 4 joint indices (0..25) per vertex
  Eigen::Matrix4Xd weights;                 // matching weights, >= 0, summing to 1 (unused slots: weight 0)
  std::vector<int> triangles;               // three vertex indices per triangle, counter-clockwise from outside
};

// Throws Error naming "<argument>.positions" / ".bones" / ".weights" / ".triangles".
void validate_skinned_mesh(const SkinnedMesh& mesh, const std::string& argument);

// The deterministic procedural hand surface around the bones of `bind` (a flat hand such as bind_frame()):
// palm slab, thumb and finger tubes with rounded ends, about `target_vertices` vertices.
SkinnedMesh make_hand_mesh(const HandFrame& bind, int target_vertices);

using BoneTransform = Eigen::Matrix<double, 3, 4>;  // [R | t]: x_world = R x_bind + t

// One blend group of the render skinning: consecutive vertices sharing the same bones, so the inner loop over
// them has no gathers and vectorizes.
struct SkinGroup {
  int begin = 0, end = 0;       // vertex range [begin, end) in HandModel::mesh order
  int count = 0;                // influences used (1..4)
  std::array<int, 4> bones{};   // joint indices of the influences
};

// Points laid out for grouped skinning: runs of consecutive points that share their influences, with the
// bind positions and weights as structure of arrays, so the inner loop has no gathers and vectorizes.
struct SkinLayout {
  std::vector<SkinGroup> groups;
  std::array<std::vector<double>, 3> bind_xyz;  // x, y, z of each bind point
  std::array<std::vector<double>, 4> weight;    // weight of influence slot k of each point's group
};

// Built once per hand (MuJoCo style: constant model, per-frame state).
struct HandModel {
  Handedness handedness = Handedness::Right;
  HandFrame bind;                     // joint poses the mesh was bound at
  std::array<Pose, kHandJointCount> bind_inverse;
  SkinnedMesh mesh;                   // render mesh, vertices REORDERED into skin groups (triangles remapped)
  std::vector<int> source_vertex;     // source_vertex[i] = index of model vertex i in the mesh given/generated
  std::vector<uint8_t> exposed;       // 1: vertex is on the skin; 0: buried inside another part (no particles)

  // Render skinning in mesh order: groups by sorted bone set (weights merged and renormalized).
  SkinLayout skin;

  // Particles: spheres at selected mesh vertices.
  std::vector<int> particle_vertex;   // mesh vertex of each particle (sorted)
  double particle_radius = 0;
  double particle_spacing = 0;        // hexagonal spacing of particle_count points over the exposed skin area
  Eigen::Matrix3Xd particle_bind;     // bind positions of the particles
  Eigen::Matrix<int, 4, Eigen::Dynamic> particle_bones;
  Eigen::Matrix4Xd particle_weights;
  // Particle skinning in particle order: runs of particles in one render group, each with its vertex's render
  // weights, so a tracked particle equals its render vertex (before deformation) bit for bit.
  SkinLayout particle_skin;

  // Local deformation of the render mesh: vertex v moves by sum_k w_k (deformed - tracked) of nearby particles.
  // Stored per particle (CSR) so a frame with few displaced particles touches few vertices.
  std::vector<int> falloff_begin;     // particle p's entries are [falloff_begin[p], falloff_begin[p+1])
  std::vector<int> falloff_vertex;
  std::vector<double> falloff_weight;
  double falloff_radius = 0;

  int particle_count() const { return int(particle_vertex.size()); }
  int vertex_count() const { return int(mesh.positions.cols()); }
};

// The procedural mesh at def.render_vertices, bound at bind_frame(def.handedness).
HandModel build_hand_model(const HandDef& def);
// A supplied mesh (e.g. from glTF) bound at `bind` (all 26 joints valid).
HandModel build_hand_model(const HandDef& def, const SkinnedMesh& mesh, const HandFrame& bind);

struct HandState {
  bool tracked = false;                                     // false: the last frame was untracked; data is stale
  std::array<BoneTransform, kHandJointCount> bones{};       // B_j of the last tracked frame
  Eigen::Matrix3Xd tracked_positions;                       // particle centres from skinning (3 x N)
  Eigen::Matrix3Xd deformed_positions;                      // after the local deformation (3 x N)
  std::vector<int> displaced;                               // particles whose deformed != tracked
  Vec3 bounds_lo = Vec3::Zero(), bounds_hi = Vec3::Zero();  // AABB of the particle spheres (tracked)
};

// Eq. 1 for the particles only. Validates the frame (argument "frame"); an untracked frame (palm or wrist
// invalid) sets state.tracked = false and keeps the previous positions. An invalid finger joint follows its
// nearest valid parent rigidly. Resets the deformation (deformed = tracked).
void pose_hand(const HandModel& model, const HandFrame& frame, HandState& state);

// Skins every render vertex (model mesh order) and applies the local deformation of state.
void skin_render(const HandModel& model, const HandState& state, Eigen::Matrix3Xd& out);

// Max over exposed mesh vertices of the distance to the nearest particle (bind pose).
double largest_particle_gap(const HandModel& model);

// ---------------------------------------------------------------------------------------------------------
// Particle contacts (closed form, the default narrow phase).

struct ParticleContact {
  int particle = -1;
  Vec3 point = Vec3::Zero();   // closest point on the body surface, world
  Vec3 normal = Vec3::UnitY(); // outward surface normal at `point`, world, unit
  double depth = 0;            // radius - signed distance of the centre; > 0 when touching
};

// A shape with what its narrow phase needs precomputed: the face planes and triangles of a convex hull,
// per-triangle bounds of a triangle mesh. Build once per body and reuse.
struct PreparedShape {
  ShapeDef shape;
  Vec3 local_lo = Vec3::Zero(), local_hi = Vec3::Zero();
  std::vector<Eigen::Vector4d> planes;   // ConvexHull: n.x, n.y, n.z, d with n.p <= d inside, |n| = 1
  std::vector<Vec3> hull_vertices;       // ConvexHull: exact input points on the hull
  std::vector<int> hull_triangles;       // ConvexHull: faces fanned into triangles
  std::vector<Vec3> tri_lo, tri_hi;      // TriangleMesh: bounds of each triangle
};
PreparedShape prepare_shape(const ShapeDef& shape, const std::string& argument = "shape");

// Appends a contact for every centre whose sphere of `radius` touches the body (depth > 0).
//  Box, Sphere, Capsule: exact closed forms. A centre inside picks the least-penetration face (box); a centre
//    exactly at a sphere centre gets normal +Y, exactly on a capsule axis +X (body frame): no NaN.
//  ConvexHull: face planes; a centre inside is exact (nearest plane); a centre outside within `radius` of the
//    planes gets the exact closest point on the hull triangles.
//  TriangleMesh: a two-sided shell: depth = radius - unsigned distance to the nearest triangle, normal from the
//    surface towards the centre (a centre never counts as inside). Brute force over triangles with bounds culling.
void collide_particles(const Eigen::Matrix3Xd& centres, double radius, const PreparedShape& shape,
                       const Pose& body_pose, std::vector<ParticleContact>& out);
void collide_particles(const Eigen::Matrix3Xd& centres, double radius, const ShapeDef& shape,
                       const Pose& body_pose, std::vector<ParticleContact>& out);

// World AABB of a shape at a pose, and the cheap test the world runs before any narrow phase
// (e.g. HandState::bounds_lo/hi against a body's world bounds).
void shape_world_bounds(const ShapeDef& shape, const Pose& pose, Vec3& lo, Vec3& hi);
inline bool bounds_overlap(const Vec3& lo_a, const Vec3& hi_a, const Vec3& lo_b, const Vec3& hi_b) {
  return (lo_a.array() <= hi_b.array()).all() && (lo_b.array() <= hi_a.array()).all();
}

// Local deformation: each particle whose centre is inside a body moves back to the body surface (the sum of
// its penetrating contacts' corrections); tracked positions are kept. Contacts must come from
// state.tracked_positions and model.particle_radius. Replaces any earlier deformation of this frame.
void deform_particles(const HandModel& model, HandState& state, const std::vector<ParticleContact>& contacts);

}  // namespace handsim
