// Linear blend skinning (eq. 1): per-point for the particles, grouped structure-of-arrays for the render mesh.
#pragma once

#include "handsim/hand.h"

namespace handsim {

// B_j = pose_j * bind_j^-1 for every joint. An invalid joint of a tracked frame follows its nearest valid
// parent rigidly (its bind offset to that parent is kept), so a lost finger joint does not tear the mesh.
// A tracked frame (palm and wrist valid). Four bones at a time where the CPU has AVX2, with the bits of
// compute_bone_transforms_scalar (the formula one bone at a time, and the path elsewhere).
void compute_bone_transforms(const HandModel& model, const HandFrame& frame,
                             std::array<BoneTransform, kHandJointCount>& bones);
void compute_bone_transforms_scalar(const HandModel& model, const HandFrame& frame,
                                    std::array<BoneTransform, kHandJointCount>& bones);

// out.col(i) = sum_k weights(k,i) * B[bones(k,i)] * bind.col(i): the per-point reference formula (the tests
// compare the grouped paths against it).
void skin_points(const Eigen::Matrix3Xd& bind, const Eigen::Matrix<int, 4, Eigen::Dynamic>& bone_ids,
                 const Eigen::Matrix4Xd& weights, const std::array<BoneTransform, kHandJointCount>& bones,
                 Eigen::Matrix3Xd& out);

// Sorts the vertices by their set of bones (stable, so neighbours stay together) and returns the permutation
// order[new] = old, with model.skin filled in that order.
std::vector<int> build_skin_groups(const SkinnedMesh& mesh, HandModel& model);

// The particles' layout: each particle takes its vertex's render group, bones and weights, so a particle is
// skinned with exactly the arithmetic of its render vertex (the two agree bit for bit). particle_vertex is
// ascending, so particles of one render group are consecutive and form one run.
constexpr int kMaxParticleRun = 32;
SkinLayout build_particle_layout(const SkinLayout& render, const std::vector<int>& particle_vertex);

// Grouped skinning of groups [first, last) of a layout into out (3 x point count, column-major). Groups write
// disjoint columns, so ranges can run on different threads and give the same bits. With `bounds` (6 doubles
// per group: min x y z, max x y z), each group's box of skinned points is written too (the contact prefilter).
void skin_layout(const SkinLayout& layout, const std::array<BoneTransform, kHandJointCount>& bones, double* out,
                 size_t first, size_t last, double* bounds = nullptr);
// Point i of the layout alone, into out[3i..3i+2] (out: as skin_layout's), with skin_layout's arithmetic: the
// same bits.
void skin_layout_point(const SkinLayout& layout, const std::array<BoneTransform, kHandJointCount>& bones, int i,
                       double* out);
void skin_layout(const SkinLayout& layout, const std::array<BoneTransform, kHandJointCount>& bones,
                 Eigen::Matrix3Xd& out, std::vector<double>* bounds = nullptr);

// skin_layout split over `threads` std::threads (the calling one included) by point count. Every point is
// computed by the same code whichever thread runs it, so the result is bit-identical to one thread.
void skin_layout_parallel(const SkinLayout& layout, const std::array<BoneTransform, kHandJointCount>& bones,
                          Eigen::Matrix3Xd& out, int threads);

// The render path: model.skin, no gathers in the inner loop. out is 3 x vertex_count.
void skin_groups(const HandModel& model, const std::array<BoneTransform, kHandJointCount>& bones,
                 Eigen::Matrix3Xd& out, int threads = 1);

// A box sure to hold every particle sphere of the hand, from the bone transforms alone (no skinning): B_k is
// rigid, so B_k p lies within |p - j_k| of B_k j_k (j_k: bind position of joint k), and a blend of such points
// lies in the box around those balls. reach[k] = max over particles influenced by bone k of |p - j_k|, plus
// the particle radius; < 0 for a bone no particle uses.
// The same per particle group (run of model.particle_skin): each group's bind points lie within
// group_radius of group_centre, so B_k of them lie within group_radius of B_k group_centre for each of its
// bones, and their blend in the box around those balls.
struct HandReach {
  std::array<Vec3, kHandJointCount> bind_joint;
  std::array<double, kHandJointCount> reach;
  std::vector<Vec3> group_centre;
  std::vector<double> group_radius;
  // Consecutive groups with the same bones (the runs of one render group) as one "span" with its own centre
  // and radius: a far span rules out all its groups with one test. span_first has one more entry than spans.
  std::vector<size_t> span_first;
  std::vector<Vec3> span_centre;
  std::vector<double> span_radius;
  // How far a group's coarse box (coarse_bounds) grown by the particle radius may reach past its bones' particle
  // reach: the most, over the groups and their bones, of |group_centre - bind_joint| + group_radius + particle
  // radius - reach. The box of coarse_particle_bounds grown by it holds every group's coarse box grown by the
  // particle radius.
  double group_excess = 0;
  // bind_joint's x, y, z and the reach by bone, padded to 28 with bone 25's, for the kernels that load four
  // bones' at once (simd4.h); the reach is -inf there for a bone that moves no particle. fill_reach_lanes.
  std::array<std::array<double, 28>, 4> lanes{};
};
HandReach build_hand_reach(const HandModel& model);
void fill_reach_lanes(HandReach& reach);
void coarse_particle_bounds(const HandReach& reach, const std::array<BoneTransform, kHandJointCount>& bones,
                            Vec3& lo, Vec3& hi);
// The same one bone at a time (coarse_particle_bounds: four at a time where the CPU has AVX2, the same box).
void coarse_particle_bounds_scalar(const HandReach& reach, const std::array<BoneTransform, kHandJointCount>& bones,
                                   Vec3& lo, Vec3& hi);
// Grows a box of coarse_particle_bounds to hold every group's coarse box grown by the particle radius
// (HandReach::group_excess, and a slack for rounding).
void hold_group_boxes(const HandReach& reach, Vec3& lo, Vec3& hi);
// A box sure to hold the centres of the points within `radius` of `centre` (bind pose) blended from the bones
// of `group`, from the bones alone (no particle radius): a group's (group_centre) or a span's.
void coarse_bounds(const SkinGroup& group, const Vec3& centre, double radius,
                   const std::array<BoneTransform, kHandJointCount>& bones, double* box);

}  // namespace handsim
