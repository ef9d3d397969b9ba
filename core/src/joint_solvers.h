// The micro-simulator of Kim & Park (Sec. III-A, eq. 4): given the parent pose P and the pose S the
// physics step (the hand) gave the child, find the joint coordinate x minimizing
//     E(x) = sum_k w_k |S v_k - C(x) v_k|^2          (least squares; the paper writes |.| unsquared)
// over the child's model vertices v_k (child frame), within the joint limits.
//
// Everything here is a pure function of plain values (Eigen matrices, Pose): no world, no Bullet, no
// globals, so bindings and benchmarks can call it directly.
#pragma once

#include "handsim/joint.h"
#include "handsim/types.h"

namespace handsim {

// ---------------------------------------------------------------------------------------------------
// Compiled joint frames (validated, normalized). Build them with make_*_frame.

struct HingeFrame {
  Vec3 pivot_parent = Vec3::Zero();
  Vec3 axis_parent = Vec3::UnitX();  // unit
  Vec3 pivot_child = Vec3::Zero();
  Quat rest = Quat::Identity();      // R0: child orientation relative to the parent at theta = 0
  double lower = -kUnlimited;
  double upper = kUnlimited;
};

struct SliderFrame {
  Vec3 anchor_parent = Vec3::Zero();
  Vec3 axis = Vec3::UnitX();  // unit, parent frame
  Vec3 anchor_child = Vec3::Zero();
  Quat rest = Quat::Identity();
  double lower = -kUnlimited;
  double upper = kUnlimited;
};

struct BallFrame {
  Vec3 pivot_parent = Vec3::Zero();
  Vec3 pivot_child = Vec3::Zero();
  Quat rest = Quat::Identity();
  Vec3 cone_axis = Vec3::UnitY();  // unit, parent frame
  double cone_half_angle = kUnlimited;  // >= pi (or inf): no limit
};

struct FixedFrame {
  Pose relative;
};

// Each validates the definition (Error naming `argument`.field) and normalizes axes and quaternions.
HingeFrame make_hinge_frame(const HingeDef& def, const std::string& argument = "hinge");
SliderFrame make_slider_frame(const SliderDef& def, const std::string& argument = "slider");
BallFrame make_ball_frame(const BallDef& def, const std::string& argument = "ball");
FixedFrame make_fixed_frame(const FixedDef& def, const std::string& argument = "fixed");

// ---------------------------------------------------------------------------------------------------
// Child vertices. The exact solvers need only the weighted moments of the vertices taken about the
// joint's point on the child (pivot or anchor). Taking them about that point, not about the body origin,
// keeps the digits when the body frame is far from its geometry (a mesh authored in world coordinates
// 10 km out): the moments then hold small numbers and nothing large cancels in the solve.

struct VertexMoments {
  Vec3 about = Vec3::Zero();           // the point the moments are taken about (child frame)
  double weight_sum = 0.0;             // W = sum w_k
  Vec3 first = Vec3::Zero();           // D1 = sum w_k d_k,        d_k = v_k - about
  Mat3 second = Mat3::Zero();          // D2 = sum w_k d_k d_k^T
  int count = 0;
};

// The vertices as the LM solvers see them, plus their moments for the exact solver.
struct JointVertices {
  Eigen::Matrix3Xd points;  // child frame, one vertex per column
  Eigen::VectorXd weights;  // empty: every weight is 1
  VertexMoments moments;
};

// Throws Error("vertices"/"weights") on no vertex, non-finite values, negative weights or zero total.
VertexMoments vertex_moments(const Eigen::Matrix3Xd& points, const Eigen::VectorXd& weights,
                             const Vec3& about);
JointVertices make_joint_vertices(Eigen::Matrix3Xd points, Eigen::VectorXd weights, const Vec3& about);

// ---------------------------------------------------------------------------------------------------
// Solver settings and results.

struct JointSolveOptions {
  int max_iterations = 10;  // LM modes; the paper's limit
  // Metres. When the weighted RMS distance of the vertices from the hinge axis (slider: never; ball: from
  // the pivot, and from the best line through it) is below this, the rotation is not observable through
  // the vertices: the solver keeps the previous value and reports Degenerate.
  double min_lever = 1e-5;
  // LmCeres only: one residual block holding all 3N residuals (true) or one 3-residual block per vertex.
  // One block is faster at every N measured (median per solve, 1 block vs N blocks: N=64 68 vs 130 us,
  // N=1182 0.95 vs 2.1 ms, N=39225 35 vs 95 ms): building and evaluating N blocks costs more than the
  // solve itself.
  bool ceres_single_block = true;
  // Hinge, Exact: false gives eq. 4's global minimum inside the limits (the reference the LM modes are
  // compared with); true gives the minimum the joint reaches by moving from `previous` — the turn of the
  // target nearest it, held at the stop on its side when beyond one. The world uses true: the global minimum
  // let a lid dragged past a stop at +165 deg jump to -165 deg in one frame, through the stop (issue 22).
  bool continuous = false;
};

struct JointSolveResult {
  double value = 0.0;  // theta (rad) or s (m)
  double cost = 0.0;   // E(value), m^2 (times the weight unit)
  int iterations = 0;  // LM iterations (accepted or not); 0 for closed forms
  JointTermination termination = JointTermination::Converged;
  double seconds = 0.0;  // wall time of the solve
};

struct BallSolveResult {
  Quat rotation = Quat::Identity();  // R, parent frame, about the pivot; identity at rest
  double cost = 0.0;
  int iterations = 0;
  JointTermination termination = JointTermination::Converged;
  double seconds = 0.0;
};

// ---------------------------------------------------------------------------------------------------
// Hinge. `previous` is the last theta: the result is unwrapped to the turn nearest it, degenerate input
// returns it, and the LM modes start from it (clamped into the limits).

// Closed form, O(1): the cost is A - (a cos(theta) + b sin(theta)), minimum at atan2(b, a). Needs
// moments about frame.pivot_child (Error "moments" otherwise). With limits, when no turn of the optimum is
// inside, the limit of smaller cost wins (ties: the one nearer `previous`).
JointSolveResult solve_hinge_exact(const HingeFrame& frame, const VertexMoments& moments, const Pose& parent,
                                   const Pose& simulated, double previous,
                                   const JointSolveOptions& options = {});
// Levenberg-Marquardt over the vertices (3 residuals each), from `previous`, at most
// options.max_iterations iterations. Limits: every trial step is clamped into [lower, upper]; a step that
// the clamp reduces to nothing ends the solve with AtLimit. Like any local method it converges to the
// nearest stationary point: started exactly at the cost maximum (previous = optimum + pi) the gradient is
// zero and it stops there ("Converged"); started near it, 10 iterations are not enough. Accuracy: with a
// zero residual it converges quadratically to the last bit; with a residual, Gauss-Newton converges
// linearly and the cost-based stop tests have a floor of ~sqrt(eps) * rms residual / rms lever radians
// (measured ~1e-9 rad for 2 mm of noise on a 0.1 m body). Use Exact when digits matter.
JointSolveResult solve_hinge_lm(const HingeFrame& frame, const JointVertices& vertices, const Pose& parent,
                                const Pose& simulated, double previous, const JointSolveOptions& options = {});
#if HANDSIM_WITH_CERES
// The paper's mode: Ceres LEVENBERG_MARQUARDT, same residuals, bounds via SetParameterLower/UpperBound.
JointSolveResult solve_hinge_lm_ceres(const HingeFrame& frame, const JointVertices& vertices,
                                      const Pose& parent, const Pose& simulated, double previous,
                                      const JointSolveOptions& options = {});
#endif
// Dispatch. LmCeres without Ceres compiled in throws Error(Unsupported, "solver").
JointSolveResult solve_hinge(JointSolver solver, const HingeFrame& frame, const JointVertices& vertices,
                             const Pose& parent, const Pose& simulated, double previous,
                             const JointSolveOptions& options = {});

Pose hinge_child_pose(const HingeFrame& frame, const Pose& parent, double theta);
// The inverse for a child pose that satisfies the hinge: the rotation angle of R0^-1-corrected relative
// orientation about the axis, unwrapped to the turn nearest `near`. Off-hinge poses: the twist part.
double hinge_angle(const HingeFrame& frame, const Pose& parent, const Pose& child, double near = 0.0);
// Metres: |pivot seen from the parent - pivot seen from the child| + length * (angle between the axis
// seen from both bodies). `length` converts the axis error to a displacement; pass the child's size.
double hinge_violation(const HingeFrame& frame, const Pose& parent, const Pose& child, double length);

// ---------------------------------------------------------------------------------------------------
// Slider. The cost is quadratic in s, so the exact solution is the weighted mean displacement along the
// axis, clamped (clamping a 1-D convex quadratic is exact). Never degenerate with W > 0.
JointSolveResult solve_slider_exact(const SliderFrame& frame, const VertexMoments& moments, const Pose& parent,
                                    const Pose& simulated, double previous,
                                    const JointSolveOptions& options = {});
JointSolveResult solve_slider_lm(const SliderFrame& frame, const JointVertices& vertices, const Pose& parent,
                                 const Pose& simulated, double previous,
                                 const JointSolveOptions& options = {});
#if HANDSIM_WITH_CERES
JointSolveResult solve_slider_lm_ceres(const SliderFrame& frame, const JointVertices& vertices,
                                       const Pose& parent, const Pose& simulated, double previous,
                                       const JointSolveOptions& options = {});
#endif
JointSolveResult solve_slider(JointSolver solver, const SliderFrame& frame, const JointVertices& vertices,
                              const Pose& parent, const Pose& simulated, double previous,
                              const JointSolveOptions& options = {});

Pose slider_child_pose(const SliderFrame& frame, const Pose& parent, double s);
double slider_displacement(const SliderFrame& frame, const Pose& parent, const Pose& child);
// Metres: distance of the child's anchor from the slide line + length * orientation error (rad).
double slider_violation(const SliderFrame& frame, const Pose& parent, const Pose& child, double length);

// ---------------------------------------------------------------------------------------------------
// Ball. Exact only (no LM mode: the closed form is exact and 3-DOF LM would add nothing but a worse
// answer). Weighted Kabsch about the pivot, with the reflection fix. Degenerate cases: vertices all near
// the pivot -> previous rotation; vertices near one line through the pivot -> the rotation nearest the
// previous one that maps the line onto its target (twist about the line kept). Cone limit: the swing
// (shortest arc taking cone_axis to R*cone_axis) is projected onto the cone along its own great circle,
// which is the exact nearest direction on the cone; the twist about cone_axis is then re-optimized in
// closed form for that swing. The result is optimal for the projected swing, not necessarily over the
// whole cone boundary.
BallSolveResult solve_ball_exact(const BallFrame& frame, const VertexMoments& moments, const Pose& parent,
                                 const Pose& simulated, const Quat& previous,
                                 const JointSolveOptions& options = {});
Pose ball_child_pose(const BallFrame& frame, const Pose& parent, const Quat& rotation);
Quat ball_rotation(const BallFrame& frame, const Pose& parent, const Pose& child);
double ball_violation(const BallFrame& frame, const Pose& parent, const Pose& child);  // metres

// ---------------------------------------------------------------------------------------------------
// Fixed: nothing to solve; the child pose is P * relative.
Pose fixed_child_pose(const FixedFrame& frame, const Pose& parent);
// Metres: position error + length * orientation error (rad).
double fixed_violation(const FixedFrame& frame, const Pose& parent, const Pose& child, double length);

}  // namespace handsim
