// The paper's micro-simulator solve (Kim & Park, Sec. III-A): Ceres Levenberg-Marquardt, at most 10
// iterations. Built only with HANDSIM_WITH_CERES. Same residuals as the Eigen LM in joint_solvers.cpp.
#include "joint_solvers.h"

#include "joint_solvers_internal.h"
#include "validate.h"

#include <ceres/ceres.h>


namespace handsim {
namespace {

// One joint model: the predicted point p_k(x) of vertex k and dp_k/dx, in the parent frame.
struct HingeModel {
  Vec3 axis;
  void predict(const Vec3& u, double theta, Vec3& p, Vec3& dp) const {
    p = Eigen::AngleAxisd(theta, axis) * u;
    dp = axis.cross(p);
  }
};

struct SliderModel {
  Vec3 axis;
  void predict(const Vec3& u, double s, Vec3& p, Vec3& dp) const {
    p = u + s * axis;
    dp = axis;
  }
};

// r_k = sqrt(w_k) (q_k - p_k(x)) for the vertices [begin, end): one vertex per block, or all in one.
template <class Model>
class VertexCost final : public ceres::CostFunction {
 public:
  VertexCost(const Model& model, const detail::VertexPairs& pairs, Eigen::Index begin, Eigen::Index end)
      : model_(model), pairs_(pairs), begin_(begin), end_(end) {
    set_num_residuals(int(3 * (end - begin)));
    mutable_parameter_block_sizes()->push_back(1);
  }

  bool Evaluate(double const* const* x, double* residuals, double** jacobians) const override {
    Vec3 p, dp;
    for (Eigen::Index k = begin_; k < end_; ++k) {
      model_.predict(pairs_.u.col(k), x[0][0], p, dp);
      const double sw = pairs_.sqrt_w[k];
      const Eigen::Index row = 3 * (k - begin_);
      Eigen::Map<Vec3>(residuals + row) = sw * (pairs_.q.col(k) - p);
      if (jacobians && jacobians[0]) Eigen::Map<Vec3>(jacobians[0] + row) = -sw * dp;
    }
    return true;
  }

 private:
  Model model_;
  const detail::VertexPairs& pairs_;
  Eigen::Index begin_, end_;
};

JointTermination termination_of(const ceres::Solver::Summary& s, double x, double lower, double upper) {
  if (s.termination_type == ceres::NO_CONVERGENCE) return JointTermination::MaxIterations;
  if (s.termination_type != ceres::CONVERGENCE)
    validate::fail("solver", "Ceres failed: " + s.message, Status::Internal);
  return (x == lower || x == upper) ? JointTermination::AtLimit : JointTermination::Converged;
}

// sum w |a x u_k|^2: how much the vertices move per radian about a (independent of theta).
double hinge_lever2(const detail::VertexPairs& p, const Vec3& a) {
  double sum = 0;
  for (Eigen::Index k = 0; k < p.u.cols(); ++k) sum += p.sqrt_w[k] * p.sqrt_w[k] * a.cross(p.u.col(k)).squaredNorm();
  return sum;
}

template <class Model>
JointSolveResult solve_ceres(const Model& model, const detail::VertexPairs& pairs, double start, double lower,
                             double upper, bool degenerate, const JointSolveOptions& o) {
  JointSolveResult r;
  double x = detail::clamp_to(start, lower, upper);
  if (degenerate) {  // same observability test as the other modes; Ceres would return any theta
    r.value = x;
    r.termination = JointTermination::Degenerate;
    return r;
  }
  ceres::Problem problem;
  const Eigen::Index n = pairs.q.cols();
  if (o.ceres_single_block) {
    problem.AddResidualBlock(new VertexCost<Model>(model, pairs, 0, n), nullptr, &x);
  } else {
    for (Eigen::Index k = 0; k < n; ++k)
      problem.AddResidualBlock(new VertexCost<Model>(model, pairs, k, k + 1), nullptr, &x);
  }
  if (std::isfinite(lower)) problem.SetParameterLowerBound(&x, 0, lower);
  if (std::isfinite(upper)) problem.SetParameterUpperBound(&x, 0, upper);

  ceres::Solver::Options opts;
  opts.minimizer_type = ceres::TRUST_REGION;
  opts.trust_region_strategy_type = ceres::LEVENBERG_MARQUARDT;
  opts.linear_solver_type = ceres::DENSE_QR;
  opts.max_num_iterations = o.max_iterations;
  opts.num_threads = 1;
  opts.logging_type = ceres::SILENT;
  opts.minimizer_progress_to_stdout = false;
  // Ceres' defaults (1e-6 relative cost change) stop far short of double precision in theta.
  opts.function_tolerance = 1e-15;
  opts.parameter_tolerance = 1e-13;
  opts.gradient_tolerance = 1e-16;
  ceres::Solver::Summary summary;
  ceres::Solve(opts, &problem, &summary);

  r.value = x;
  r.cost = 2 * summary.final_cost;  // Ceres reports 1/2 sum r^2
  r.iterations = int(summary.iterations.size()) - 1;  // entry 0 is the starting point
  r.termination = termination_of(summary, x, lower, upper);
  return r;
}

}  // namespace

JointSolveResult solve_hinge_lm_ceres(const HingeFrame& f, const JointVertices& v, const Pose& parent,
                                      const Pose& simulated, double previous, const JointSolveOptions& o) {
  detail::Stopwatch clock;
  detail::check_vertices_about(v, f.pivot_child);
  detail::check_previous(previous);
  auto t = detail::relative_target(parent, simulated, f.pivot_child, f.pivot_parent);
  detail::VertexPairs pairs = detail::vertex_pairs(v, f.pivot_child, t, f.rest);
  bool degenerate = hinge_lever2(pairs, f.axis_parent) <= v.moments.weight_sum * o.min_lever * o.min_lever;
  JointSolveResult r = solve_ceres(HingeModel{f.axis_parent}, pairs, previous, f.lower, f.upper, degenerate, o);
  r.seconds = clock.seconds();
  return r;
}

JointSolveResult solve_slider_lm_ceres(const SliderFrame& f, const JointVertices& v, const Pose& parent,
                                       const Pose& simulated, double previous, const JointSolveOptions& o) {
  detail::Stopwatch clock;
  detail::check_vertices_about(v, f.anchor_child);
  detail::check_previous(previous);
  auto t = detail::relative_target(parent, simulated, f.anchor_child, f.anchor_parent);
  detail::VertexPairs pairs = detail::vertex_pairs(v, f.anchor_child, t, f.rest);
  JointSolveResult r = solve_ceres(SliderModel{f.axis}, pairs, previous, f.lower, f.upper, false, o);
  r.seconds = clock.seconds();
  return r;
}

}  // namespace handsim
