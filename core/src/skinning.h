// Linear blend skinning (eq. 1): per-point for the particles, grouped structure-of-arrays for the render mesh.
#pragma once

#include "handsim/hand.h"

namespace handsim {

// B_j = pose_j * bind_j^-1 for every joint. An invalid joint of a tracked frame follows its nearest valid
// parent rigidly (its bind offset to that parent is kept), so a lost finger joint does not tear the mesh.
void compute_bone_transforms(const HandModel& model, const HandFrame& frame,
                             std::array<BoneTransform, kHandJointCount>& bones);

// out.col(i) = sum_k weights(k,i) * B[bones(k,i)] * bind.col(i): the per-point path (particles).
void skin_points(const Eigen::Matrix3Xd& bind, const Eigen::Matrix<int, 4, Eigen::Dynamic>& bone_ids,
                 const Eigen::Matrix4Xd& weights, const std::array<BoneTransform, kHandJointCount>& bones,
                 Eigen::Matrix3Xd& out);

// Sorts the vertices by their set of bones (stable, so neighbours stay together) and returns the permutation
// order[new] = old, with the groups and the SoA arrays of the model filled in that order.
std::vector<int> build_skin_groups(const SkinnedMesh& mesh, HandModel& model);

// The render path: grouped, no gathers in the inner loop. out is 3 x vertex_count.
void skin_groups(const HandModel& model, const std::array<BoneTransform, kHandJointCount>& bones,
                 Eigen::Matrix3Xd& out);

}  // namespace handsim
