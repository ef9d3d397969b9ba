/* Every public enum of handsim, once. Each value is a row X(Enum, Value, number, UPPER, C_CONSTANT):
 *   handsim::Enum::Value = number in C++ (the C++ enums are declared from these rows), Enum.UPPER in Python,
 *   C_CONSTANT in handsim.h, Handsim.Enum.Value in C#.
 * The bindings are produced from or checked against these rows: the C++ enums and the pybind11 enums are made
 * from them, c_library.cpp static_asserts every C constant, and the C, C# and Python tests walk every row
 * (docs/design.md, "One table per enum and per def"). Preprocessor only, valid C, so the C host test includes it.
 * Numbers are part of the C ABI: never renumber, only append. */
#ifndef HANDSIM_ENUM_TABLE_H
#define HANDSIM_ENUM_TABLE_H

/* What a call returned; the C ABI's status codes. */
#define HANDSIM_ENUM_STATUS(X)                                                                            \
  X(Status, Ok, 0, OK, HANDSIM_OK)                                                                        \
  /* a value is out of its domain (NaN, negative size, bad shape, ...) */                                 \
  X(Status, InvalidArgument, 1, INVALID_ARGUMENT, HANDSIM_INVALID_ARGUMENT)                               \
  /* an id names a removed object or comes from another world */                                          \
  X(Status, StaleId, 2, STALE_ID, HANDSIM_STALE_ID)                                                       \
  /* the call is not allowed now (e.g. removing a body a joint still uses) */                             \
  X(Status, InvalidState, 3, INVALID_STATE, HANDSIM_INVALID_STATE)                                        \
  /* the build lacks the feature (e.g. Ceres solver without HANDSIM_WITH_CERES) */                        \
  X(Status, Unsupported, 4, UNSUPPORTED, HANDSIM_UNSUPPORTED)                                             \
  /* a bug: an invariant broke; the message says which */                                                \
  X(Status, Internal, 5, INTERNAL, HANDSIM_INTERNAL)

#define HANDSIM_ENUM_SHAPE_TYPE(X)                                                                        \
  X(ShapeType, Box, 0, BOX, HANDSIM_SHAPE_BOX)                                                            \
  X(ShapeType, Sphere, 1, SPHERE, HANDSIM_SHAPE_SPHERE)                                                   \
  X(ShapeType, Capsule, 2, CAPSULE, HANDSIM_SHAPE_CAPSULE)                                                \
  X(ShapeType, ConvexHull, 3, CONVEX_HULL, HANDSIM_SHAPE_CONVEX_HULL)                                     \
  X(ShapeType, TriangleMesh, 4, TRIANGLE_MESH, HANDSIM_SHAPE_TRIANGLE_MESH)

#define HANDSIM_ENUM_HANDEDNESS(X)                                                                        \
  X(Handedness, Left, 0, LEFT, HANDSIM_LEFT)                                                              \
  X(Handedness, Right, 1, RIGHT, HANDSIM_RIGHT)

/* How the collision particles are chosen among the mesh vertices. */
#define HANDSIM_ENUM_PARTICLE_SAMPLING(X)                                                                 \
  /* the paper: seeded uniform choice among the mesh vertices */                                          \
  X(ParticleSampling, Random, 0, RANDOM, HANDSIM_SAMPLING_RANDOM)                                         \
  /* farthest-point sampling: even coverage, smaller largest gap */                                       \
  X(ParticleSampling, Even, 1, EVEN, HANDSIM_SAMPLING_EVEN)

/* How the micro-simulator (Kim & Park, Sec. III-A, eq. 4) finds the joint coordinate. */
#define HANDSIM_ENUM_JOINT_SOLVER(X)                                                                      \
  /* closed form (default): O(1) per solve from precomputed vertex moments */                             \
  X(JointSolver, Exact, 0, EXACT, HANDSIM_SOLVER_EXACT)                                                   \
  /* Levenberg-Marquardt over the vertices, Eigen, no Ceres needed */                                     \
  X(JointSolver, Lm, 1, LM, HANDSIM_SOLVER_LM)                                                            \
  /* the paper's mode: Ceres Levenberg-Marquardt; needs HANDSIM_WITH_CERES */                             \
  X(JointSolver, LmCeres, 2, LM_CERES, HANDSIM_SOLVER_LM_CERES)

/* How the world keeps a joint together. */
#define HANDSIM_ENUM_JOINT_MODEL(X)                                                                       \
  /* reduced coordinates through the micro-simulator (default): never drifts apart */                     \
  X(JointModel, Hard, 0, HARD, HANDSIM_MODEL_HARD)                                                        \
  /* Bullet btHingeConstraint & co. baseline: may stretch under large hand forces */                      \
  X(JointModel, Soft, 1, SOFT, HANDSIM_MODEL_SOFT)

/* How the micro-simulator's last solve ended. */
#define HANDSIM_ENUM_JOINT_TERMINATION(X)                                                                 \
  /* exact: the unconstrained optimum was inside the limits; LM: step/gradient tolerance */               \
  X(JointTermination, Converged, 0, CONVERGED, HANDSIM_TERMINATION_CONVERGED)                             \
  /* LM ran out of iterations; value is the last accepted iterate */                                      \
  X(JointTermination, MaxIterations, 1, MAX_ITERATIONS, HANDSIM_TERMINATION_MAX_ITERATIONS)               \
  /* the cost does not depend on the coordinate (enough): value is the previous one */                    \
  X(JointTermination, Degenerate, 2, DEGENERATE, HANDSIM_TERMINATION_DEGENERATE)                          \
  /* the result sits on a limit because the optimum lies beyond it */                                     \
  X(JointTermination, AtLimit, 3, AT_LIMIT, HANDSIM_TERMINATION_AT_LIMIT)

/* Hand particles against objects (WorldDef::particle_contacts). */
#define HANDSIM_ENUM_PARTICLE_CONTACTS(X)                                                                 \
  /* the core's closed-form narrow phase (default) */                                                     \
  X(ParticleContacts, ClosedForm, 0, CLOSED_FORM, HANDSIM_CONTACTS_CLOSED_FORM)                           \
  /* one Bullet collision object per particle, as in the paper (a baseline; same contacts, ~100x cost) */ \
  X(ParticleContacts, BulletObjects, 1, BULLET_OBJECTS, HANDSIM_CONTACTS_BULLET_OBJECTS)

/* How a hand moves a free body it touches but does not hold (WorldDef::push_model; docs/grasp.md "Push models"). */
#define HANDSIM_ENUM_PUSH_MODEL(X)                                                                        \
  /* eq. 2: the hands' velocity at the body plus the least-squares fit of the overlap, per frame */ \
  X(PushModel, Fit, 0, FIT, HANDSIM_PUSH_FIT)                                                             \
  /* the pulp's bounded normal and friction impulses; the overlap removed as a displacement, no velocity */ \
  X(PushModel, Physical, 1, PHYSICAL, HANDSIM_PUSH_PHYSICAL)                                             \
  /* (default) physical, but a hand closing its grip (GraspSettings::closing_distance) only presses */ \
  X(PushModel, Wrap, 2, WRAP, HANDSIM_PUSH_WRAP)

#define HANDSIM_ENUM_BODY_MOTION(X)                                                                       \
  X(BodyMotion, Static, 0, STATIC, HANDSIM_MOTION_STATIC)                                                 \
  X(BodyMotion, Dynamic, 1, DYNAMIC, HANDSIM_MOTION_DYNAMIC)                                              \
  /* moved only by poses the caller, the hand or a joint sets; a grasped dynamic body is kinematic */     \
  X(BodyMotion, Kinematic, 2, KINEMATIC, HANDSIM_MOTION_KINEMATIC)

#define HANDSIM_ENUM_EVENT_TYPE(X)                                                                        \
  X(EventType, ContactBegin, 0, CONTACT_BEGIN, HANDSIM_EVENT_CONTACT_BEGIN)                               \
  X(EventType, ContactEnd, 1, CONTACT_END, HANDSIM_EVENT_CONTACT_END)                                     \
  X(EventType, GraspBegin, 2, GRASP_BEGIN, HANDSIM_EVENT_GRASP_BEGIN)                                     \
  X(EventType, GraspEnd, 3, GRASP_END, HANDSIM_EVENT_GRASP_END)

/* Why a grasp ended (GraspEnd events only; None otherwise). */
#define HANDSIM_ENUM_EVENT_REASON(X)                                                                      \
  X(EventReason, None, 0, NONE, HANDSIM_REASON_NONE)                                                      \
  /* the hand let go: no hold for GraspSettings::release_time_s (or it opened) */                         \
  X(EventReason, Released, 1, RELEASED, HANDSIM_REASON_RELEASED)                                          \
  /* the hand was untracked for longer than GraspSettings::tracking_grace_s */                            \
  X(EventReason, TrackingLost, 2, TRACKING_LOST, HANDSIM_REASON_TRACKING_LOST)                            \
  X(EventReason, BodyRemoved, 3, BODY_REMOVED, HANDSIM_REASON_BODY_REMOVED)                               \
  X(EventReason, HandRemoved, 4, HAND_REMOVED, HANDSIM_REASON_HAND_REMOVED)

#define HANDSIM_ENUM_JOINT_TYPE(X)                                                                        \
  X(JointType, Hinge, 0, HINGE, HANDSIM_JOINT_HINGE)                                                      \
  X(JointType, Slider, 1, SLIDER, HANDSIM_JOINT_SLIDER)                                                   \
  X(JointType, Ball, 2, BALL, HANDSIM_JOINT_BALL)                                                         \
  X(JointType, Fixed, 3, FIXED, HANDSIM_JOINT_FIXED)

/* The stages of one step (Algorithm 1 of Kim & Park), in the order they run. What a stage's `work` counts:
 * skinning: tracked hands; contacts: hand-body pairs near enough to test; deformation: particles pushed back;
 * grasp: hand-body pairs decided; attach: grasped bodies moved with their hand; pose_fit: touched free bodies
 * fitted (eq. 2); dynamics: substeps; joints: live joints; slip: second-hand grasps re-taken (eq. 5). */
#define HANDSIM_ENUM_STAGE(X)                                                                             \
  X(Stage, Skinning, 0, SKINNING, HANDSIM_STAGE_SKINNING)                                                 \
  X(Stage, Contacts, 1, CONTACTS, HANDSIM_STAGE_CONTACTS)                                                 \
  X(Stage, Deformation, 2, DEFORMATION, HANDSIM_STAGE_DEFORMATION)                                        \
  X(Stage, Grasp, 3, GRASP, HANDSIM_STAGE_GRASP)                                                          \
  X(Stage, Attach, 4, ATTACH, HANDSIM_STAGE_ATTACH)                                                       \
  X(Stage, PoseFit, 5, POSE_FIT, HANDSIM_STAGE_POSE_FIT)                                                  \
  X(Stage, Dynamics, 6, DYNAMICS, HANDSIM_STAGE_DYNAMICS)                                                 \
  X(Stage, Joints, 7, JOINTS, HANDSIM_STAGE_JOINTS)                                                       \
  X(Stage, Slip, 8, SLIP, HANDSIM_STAGE_SLIP)

/* Why a stage had nothing to do in the last step; None: it ran. */
#define HANDSIM_ENUM_SKIP_REASON(X)                                                                       \
  X(SkipReason, None, 0, NONE, HANDSIM_SKIP_NONE)                                                         \
  X(SkipReason, NoTrackedHand, 1, NO_TRACKED_HAND, HANDSIM_SKIP_NO_TRACKED_HAND)                          \
  X(SkipReason, NoHandNearBody, 2, NO_HAND_NEAR_BODY, HANDSIM_SKIP_NO_HAND_NEAR_BODY)                     \
  X(SkipReason, NoParticleInside, 3, NO_PARTICLE_INSIDE, HANDSIM_SKIP_NO_PARTICLE_INSIDE)                 \
  X(SkipReason, NoMovableBodyTouched, 4, NO_MOVABLE_BODY_TOUCHED, HANDSIM_SKIP_NO_MOVABLE_BODY_TOUCHED)   \
  X(SkipReason, NothingGrasped, 5, NOTHING_GRASPED, HANDSIM_SKIP_NOTHING_GRASPED)                         \
  X(SkipReason, NoFreeBodyTouched, 6, NO_FREE_BODY_TOUCHED, HANDSIM_SKIP_NO_FREE_BODY_TOUCHED)            \
  /* the accumulated dt is still shorter than one fixed substep */                                        \
  X(SkipReason, BelowSubstep, 7, BELOW_SUBSTEP, HANDSIM_SKIP_BELOW_SUBSTEP)                               \
  X(SkipReason, NoJoints, 8, NO_JOINTS, HANDSIM_SKIP_NO_JOINTS)                                           \
  X(SkipReason, NoSecondHand, 9, NO_SECOND_HAND, HANDSIM_SKIP_NO_SECOND_HAND)

/* What a step dropped or recovered from, silently before. The number is a bit index: the step report's
 * `warnings` has bit (1 << number) set for each warning raised. */
#define HANDSIM_ENUM_STEP_WARNING(X)                                                                      \
  /* dt exceeded max_substeps fixed substeps; the rest was dropped (StepReport::dropped_seconds) */       \
  X(StepWarning, SubstepsDropped, 0, SUBSTEPS_DROPPED, HANDSIM_WARNING_SUBSTEPS_DROPPED)                  \
  /* Bullet returned a non-finite body state; the body kept its last finite pose, at rest */              \
  X(StepWarning, NonFiniteRecovered, 1, NON_FINITE_RECOVERED, HANDSIM_WARNING_NON_FINITE_RECOVERED)       \
  /* a palm moved faster than the speed cap: its motion history was cleared (what it holds arrives at rest) */ \
  X(StepWarning, HandTeleported, 2, HAND_TELEPORTED, HANDSIM_WARNING_HAND_TELEPORTED)

/* Every row of every enum above, in this order. */
#define HANDSIM_ENUM_VALUES(X)                                                                            \
  HANDSIM_ENUM_STATUS(X)                                                                                  \
  HANDSIM_ENUM_SHAPE_TYPE(X)                                                                              \
  HANDSIM_ENUM_HANDEDNESS(X)                                                                              \
  HANDSIM_ENUM_PARTICLE_SAMPLING(X)                                                                       \
  HANDSIM_ENUM_JOINT_SOLVER(X)                                                                            \
  HANDSIM_ENUM_JOINT_MODEL(X)                                                                             \
  HANDSIM_ENUM_JOINT_TERMINATION(X)                                                                       \
  HANDSIM_ENUM_PARTICLE_CONTACTS(X)                                                                       \
  HANDSIM_ENUM_BODY_MOTION(X)                                                                             \
  HANDSIM_ENUM_EVENT_TYPE(X)                                                                              \
  HANDSIM_ENUM_EVENT_REASON(X)                                                                            \
  HANDSIM_ENUM_JOINT_TYPE(X)                                                                              \
  HANDSIM_ENUM_STAGE(X)                                                                                   \
  HANDSIM_ENUM_SKIP_REASON(X)                                                                             \
  HANDSIM_ENUM_STEP_WARNING(X)                                                                            \
  HANDSIM_ENUM_PUSH_MODEL(X)

#endif /* HANDSIM_ENUM_TABLE_H */
