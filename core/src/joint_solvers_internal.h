// Pieces shared by joint_solvers.cpp and joint_solvers_ceres.cpp. Not installed, not for bindings.
#pragma once

#include "joint_solvers.h"

#include <chrono>

namespace handsim::detail {

// The simulated pose seen from the parent, reduced to what the joint needs. For a vertex d_k (child frame,
// about the child's joint point) the target in the parent frame, about the parent's joint point, is
//   q_k = rotation * d_k + offset.
// offset is computed as R_P^T (R_S p_c + (t_S - t_P)) - p_p: the two world translations are subtracted
// first, so a scene 10 km out loses only the digits of that one difference.
struct RelativeTarget {
  Mat3 rotation;
  Vec3 offset;
};
RelativeTarget relative_target(const Pose& parent, const Pose& simulated, const Vec3& point_child,
                               const Vec3& point_parent);

// Per-vertex data for the LM modes, in the parent frame about the parent's joint point:
// target q_k, rest-model u_k = R0 d_k, and sqrt(w_k).
struct VertexPairs {
  Eigen::Matrix3Xd q;
  Eigen::Matrix3Xd u;
  Eigen::VectorXd sqrt_w;
};
VertexPairs vertex_pairs(const JointVertices& vertices, const Vec3& about_child, const RelativeTarget& target,
                         const Quat& rest);

// sum_k w_k |M d_k + e|^2 from the moments (d_k about moments.about).
double rigid_cost(const Mat3& m, const Vec3& e, const VertexMoments& moments);

double clamp_to(double x, double lower, double upper);
void check_previous(double previous);
void check_vertices_about(const JointVertices& vertices, const Vec3& about);

class Stopwatch {
 public:
  double seconds() const {
    return std::chrono::duration<double>(std::chrono::steady_clock::now() - start_).count();
  }

 private:
  std::chrono::steady_clock::time_point start_ = std::chrono::steady_clock::now();
};

}  // namespace handsim::detail
