// The World: bodies, hands and joints, stepped frame by frame (Algorithm 1 of Kim & Park).
// Settings structs with defaults ("defs") describe what to create; the world returns opaque ids.
#pragma once

#include "handsim/grasp_settings.h"
#include "handsim/hand.h"
#include "handsim/joint.h"
#include "handsim/shape.h"
#include "handsim/step_report.h"
#include "handsim/types.h"

#include <cstdint>
#include <memory>
#include <mutex>
#include <vector>

namespace handsim {

HANDSIM_DECLARE_ENUM(ParticleContacts, HANDSIM_ENUM_PARTICLE_CONTACTS);
HANDSIM_DECLARE_ENUM(PushModel, HANDSIM_ENUM_PUSH_MODEL);

// One hand's input to a step: the frame that drives the hand `hand` (World::step).
struct HandInput {
  HandId hand;
  HandFrame frame;
};

struct WorldDef {
  Vec3 gravity = Vec3(0, -9.81, 0);
  // Physics runs at a fixed substep so results do not depend on the caller's frame rate; a frame's dt is
  // accumulated and consumed in whole substeps (at most max_substeps per step, the rest is dropped so a
  // long hitch cannot make the next frame explode in cost).
  double fixed_substep = 1.0 / 240.0;
  int max_substeps = 8;
  bool ground = true;  // an infinite static plane y = ground_height
  double ground_height = 0.0;
  double ground_friction = 0.5;
  // Bullet's sequential-impulse iterations per substep. They matter only for free-body contacts and for
  // JointModel::Soft joints; hard joints are solved in closed form by the core.
  int solver_iterations = 10;
  // Levenberg-Marquardt iteration cap of the micro-simulator's Lm / LmCeres modes (the paper's 10).
  int joint_max_iterations = 10;
  GraspSettings grasp;
  // Hand particles against objects: the core's closed-form narrow phase (default), or one Bullet collision
  // object per particle as in the paper (a baseline for benchmarks; same contacts, ~100x the cost).
  using ParticleContacts = handsim::ParticleContacts;
  ParticleContacts particle_contacts = ParticleContacts::ClosedForm;
  // The paper's pipeline, as a baseline for benchmarks: every stage runs every step whether the scene needs
  // it or not (no bounds culling of hand-body pairs, render mesh skinned every step, hard joints solved with
  // Ceres LM when built with Ceres). Combine with ParticleContacts::BulletObjects for the full paper mode.
  bool paper_pipeline = false;
  // Threads that skin the render mesh when it is read (1..64). Every vertex is computed by the same code
  // whichever thread runs it, so the vertices are bit-identical to one thread. A build without threads
  // (HANDSIM_WITH_THREADS=OFF) accepts the setting and uses one.
  int render_threads = 1;
  // The contact skin (docs/grasp.md "First touch"). A particle's overlap with a free body up to skin_depth is
  // compressed finger pulp, not bone: such shallow contacts press the body with the pulp's pressure, which
  // grows with the compression to skin_pressure at skin_depth, as impulses at the contact points that Bullet
  // resolves with the ground and the other bodies; only the overlap beyond skin_depth moves the body
  // kinematically (eq. 2). So a hand laid onto a resting body presses it onto its support instead of fitting
  // it to the skin's curvature. 0 turns the skin off: every overlap is pushed out by eq. 2, as in the paper.
  // 3 mm: about what fingertip pulp compresses under a few newtons before the bone takes the load.
  // 20 kPa: the pulp's contact pressure at that compression (a few N over the 1-2 cm^2 a pressed fingertip
  // touches), well below the ~0.5 MPa where pressure starts to hurt.
  double skin_depth = 0;       // m, 0 .. 0.05
  double skin_pressure = 20e3; // Pa, 0 .. 1e6
  // How a hand moves a free body it touches but does not hold (docs/grasp.md "Push models"). Fit: eq. 2, the
  // touching hands' velocity at the body plus the least-squares fit of the overlap, both given to the body as
  // velocity. Physical: the pulp pushes with impulses at the contacts, along the normals (never pulling)
  // and by Coulomb friction along the surface, each bounded by what the pulp passes in the frame (skin_pressure
  // over the particle's skin area for dt); the overlap beyond skin_depth is removed as the least displacement,
  // with no velocity, so a graze leaves no momentum in the body. Wrap (default): Physical, but a hand closing its
  // grip (GraspSettings::closing_distance within closing_window_s) only presses, and its digits do not displace a
  // free body; its overlap is not removed. The default since session 17: it leads Fit in every column of the judge
  // and the simulated users (docs/grasp.md "Wrap as the default, measured").
  using PushModel = handsim::PushModel;
  PushModel push_model = PushModel::Wrap;
};

struct BodyDef {
  ShapeDef shape;
  double mass = 1.0;  // kg; 0 makes a static body
  Pose pose;
  Vec3 linear_velocity = Vec3::Zero();
  Vec3 angular_velocity = Vec3::Zero();  // rad/s, world frame
  double friction = 0.5;
  double restitution = 0.0;
  bool kinematic = false;  // moved only by set_body_pose / the hand, never by forces
};

HANDSIM_DECLARE_ENUM(BodyMotion, HANDSIM_ENUM_BODY_MOTION);

// Who holds a body. The primary hand moves it (pose = palm pose * relative pose); a secondary hand on the
// same body has its relative pose re-taken every frame (eq. 5), so it slides instead of fighting.
struct GraspInfo {
  bool grasped = false;
  HandId primary;
  HandId secondary;
  Pose primary_relative;  // body pose in the primary hand's palm frame
};

HANDSIM_DECLARE_ENUM(EventType, HANDSIM_ENUM_EVENT_TYPE);
HANDSIM_DECLARE_ENUM(EventReason, HANDSIM_ENUM_EVENT_REASON);

// Events of the last step, pulled after it (no callbacks). Events raised by remove_body / remove_hand
// between steps are listed at once and stay listed through the next step.
struct Event {
  EventType type = EventType::ContactBegin;
  HandId hand;
  BodyId body;
  EventReason reason = EventReason::None;  // GraspEnd only
};

HANDSIM_DECLARE_ENUM(JointType, HANDSIM_ENUM_JOINT_TYPE);

// One joint after the last step.
struct JointState {
  JointType type = JointType::Hinge;
  JointModel model = JointModel::Hard;
  JointSolver solver = JointSolver::Exact;
  BodyId parent;  // null: the world
  BodyId child;
  double value = 0;  // hinge: theta (rad); slider: s (m); ball, fixed: 0
  double rate = 0;   // d value / dt
  Quat rotation = Quat::Identity();  // ball: R (parent frame, identity at rest)
  // Where the joint is, world frame, from the parent's pose: the hinge/ball pivot or the slider anchor (fixed:
  // the child's origin as the parent holds it), the hinge/slider axis or the ball's cone axis (fixed: zero),
  // and the limits (rad: hinge, and the ball cone's half angle as `upper`; m: slider; +-inf: none). A viewer
  // draws joints from these; nothing in a step reads them.
  Vec3 anchor = Vec3::Zero();
  Vec3 axis = Vec3::Zero();
  double lower = -kUnlimited, upper = kUnlimited;
  // Metres, measured from the two bodies' poses: how far the joint is pulled apart. Hard joints: rounding
  // only; soft joints: the rubber band.
  double violation = 0;
  // Radians (hinge) or metres (slider) beyond a limit, measured from the poses; 0 inside the limits.
  double overshoot = 0;
  // The micro-simulator's solve of the last step (the child was grasped or pushed); solved = false and the
  // rest zero otherwise (cleared at the start of every step).
  bool solved = false;
  double cost = 0;
  int iterations = 0;
  JointTermination termination = JointTermination::Converged;
  double solve_seconds = 0;
};

// Thread safety: every member function may be called from any thread. Calls on one world are serialised by
// the world's mutex (the second caller waits; see docs/design.md "Threads"); different worlds share nothing
// and run in parallel. Results are returned by value, so nothing a caller holds is changed by another
// thread's call — except hand_model(), whose reference stays valid until that hand is removed or reset().
class World {
 public:
  explicit World(const WorldDef& def = {});
  ~World();
  World(World&&) noexcept;
  World& operator=(World&&) noexcept;
  World(const World&) = delete;
  World& operator=(const World&) = delete;

  WorldDef def() const;
  // Removes every body, joint and hand and resets time; the WorldDef is kept. Every grasp and contact it ends
  // is reported (GraspEnd / ContactEnd with reason BodyRemoved) in events() until the next step.
  void reset();

  // --- bodies ---
  BodyId add_body(const BodyDef& def);
  void remove_body(BodyId id);  // Status::InvalidState while a joint uses it
  bool contains(BodyId id) const;
  std::vector<BodyId> bodies() const;
  ShapeDef body_shape(BodyId id) const;
  double body_mass(BodyId id) const;
  BodyMotion body_motion(BodyId id) const;

  Pose body_pose(BodyId id) const;
  // Teleport; velocities are kept. A held body stays held at the new pose (relative poses re-taken).
  void set_body_pose(BodyId id, const Pose& pose);
  Vec3 body_linear_velocity(BodyId id) const;
  Vec3 body_angular_velocity(BodyId id) const;
  void set_body_velocity(BodyId id, const Vec3& linear, const Vec3& angular);

  // --- joints ---
  // A hard joint's child is moved by the joint only: it stays on the joint and inside its limits in every
  // situation (grasped, pushed, falling). A body may be the child of one hard joint; the joint's parent may
  // itself be a child (chains and trees, no loops). Status::InvalidState for a second hard joint on the same
  // child, a loop, or a static/kinematic child.
  JointId add_joint(const HingeDef& def);
  JointId add_joint(const SliderDef& def);
  JointId add_joint(const BallDef& def);
  JointId add_joint(const FixedDef& def);
  // The child becomes a free body again, keeping its velocity.
  void remove_joint(JointId id);
  bool contains(JointId id) const;
  std::vector<JointId> joints() const;
  JointState joint_state(JointId id) const;
  // Hinge / slider: teleport the child to this coordinate (clamped to the limits) at rest.
  void set_joint_value(JointId id, double value);

  // --- hands ---
  // A hand with the procedural mesh, or with a supplied skinned mesh bound at `bind` (e.g. from glTF).
  HandId add_hand(const HandDef& def);
  HandId add_hand(const HandDef& def, const SkinnedMesh& mesh, const HandFrame& bind);
  void remove_hand(HandId id);
  bool contains(HandId id) const;
  std::vector<HandId> hands() const;
  const HandModel& hand_model(HandId id) const;
  bool hand_tracked(HandId id) const;
  Pose hand_palm_pose(HandId id) const;  // of the last tracked frame
  // 3 x N particle centres: where the tracked hand is, and where it is drawn after the local deformation.
  Eigen::Matrix3Xd hand_particles(HandId id, bool deformed) const;
  // All render vertices, skinned on demand (only when someone asks), with the local deformation.
  Eigen::Matrix3Xd hand_render_vertices(HandId id);

  // --- grasps, contacts, events ---
  GraspInfo body_grasp(BodyId id) const;
  int body_contact_count(BodyId body, HandId hand) const;  // touching particles in the last step
  // Those contacts themselves (particle, surface point, normal, depth), sorted by particle: what a viewer
  // colours and what a debugger inspects, without re-deriving the narrow phase outside the core.
  std::vector<ParticleContact> body_contacts(BodyId body, HandId hand) const;
  std::vector<Event> events() const;

  // --- stepping ---
  StepReport step(double dt);
  // One frame of Algorithm 1: hands[k].frame drives the hand hands[k].hand; a live hand without an entry is
  // untracked this frame. A null, stale or repeated id is refused naming hands[k].hand (StaleId for a hand
  // that is not in this world, InvalidArgument for a repeat). Everything is validated before anything
  // changes. Returns what the step did, as last_step() does until the next step.
  StepReport step(double dt, const std::vector<HandInput>& hands);
  // Deprecated (kept for one version, docs/design.md "Hands addressed by id"): hands[i] drives the i-th hand
  // of hands(). A freed hand slot is reused by the next add_hand, so after remove_hand(a); add_hand(c) the
  // frame meant for the hand after a drives c; the overload above cannot mix hands up.
  StepReport step(double dt, const std::vector<HandFrame>& hands);
  double time() const;
  StepReport last_step() const;       // all zero before the first step and after reset()
  std::string stage_summary() const;  // summary(last_step()): which stages ran, what they cost, why

  // A stable 64-bit FNV-1a hash of everything that decides the world's future (what save_state saves but the
  // caches: bodies, joints, Bullet's copies of the bodies and their sleep, grasp trackers, entry faces, hand
  // histories, the clock and the substep accumulator; bits of the doubles), identical across runs and
  // processes for the same inputs. Generations and free slots are not state.
  uint64_t state_hash() const;

  // --- save and restore (docs/design.md "Save and restore") ---
  // The world's state as bytes (a versioned header, then the state; format in docs/design.md). The world's
  // Bullet scene is rebuilt from them here, as restore_state rebuilds it, so this world and every world
  // restored from the bytes continue bit for bit alike (Bullet's contact caches start afresh in both).
  std::vector<uint8_t> save_state();
  // Puts the world in the saved state. The world must be built alike: the same WorldDef and the same adds
  // and removes of bodies, joints and hands (so the same slots, shapes, masses, joints and hands); ids stay
  // this world's. events() and stage_reports() are emptied. Bad bytes (truncated, corrupt, another format
  // version, another world): Error naming "state", world unchanged.
  void restore_state(const std::vector<uint8_t>& state);
  void restore_state(const uint8_t* data, size_t size);

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
  // Held by every member function for its whole call (a pointer so that World stays movable).
  std::unique_ptr<std::mutex> mutex_;
  std::unique_lock<std::mutex> lock() const { return std::unique_lock<std::mutex>(*mutex_); }
  friend struct WorldInternals;  // tests/cpp/world_internals.h: white-box access for test_state.cpp and test_hold.cpp
};

}  // namespace handsim
