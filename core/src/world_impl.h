// The world's model and state, shared by world.cpp (the public API), world_step.cpp (Algorithm 1) and the
// files of its stages (skinning, contacts, deformation, grasp, pose_fit, dynamics, world_joints,
// world_activity, world_state).
#pragma once

#include "bit_memo.h"
#include "handsim/world.h"

#include "bullet_backend.h"
#include "contacts.h"
#include "grasp.h"
#include "bullet_particles.h"
#include "joint_solvers.h"
#include "skinning.h"
#include "validate.h"

#include <array>
#include <map>
#include <memory>
#include <vector>

namespace handsim {

// Each object is split into its model -- built once when it is added, never changed by a step: shape, inertia,
// joint frames, hand models, the Bullet handles -- and its state, which the step changes and which decides the
// future: poses, velocities, grasps, joint coordinates, hand histories. save_state, restore_state and the
// state hash walk the states (world_state.cpp); the model fingerprint covers the models. See docs/design.md
// "Model and state".

struct BodyModel {
  ShapeDef shape;
  PreparedShape prepared;  // narrow-phase data for hand particles, built once
  double mass = 0;
  double friction = 0.5, restitution = 0;  // as given; Bullet holds them, a rebuilt Bullet scene needs them
  BodyMotion declared = BodyMotion::Static;  // what the BodyDef asked for
  Vec3 unit_inertia = Vec3::Ones();  // principal moments per kg, body frame (for hard joints' dynamics)
  int backend = -1;
  int hard_joint = -1;  // index of the hard joint whose child this is, or -1
  int soft_joint = -1;  // index of a soft joint whose child this is (driven by the hand, not attached)

  bool jointed() const { return hard_joint >= 0; }
};

struct BodyState {
  BodyMotion motion = BodyMotion::Static;  // now: a grasped dynamic body is kinematic
  Pose pose;
  Pose synced_pose;  // kinematic bodies: the pose Bullet last saw, for interpolating across substeps
  Vec3 linear = Vec3::Zero();
  Vec3 angular = Vec3::Zero();
  GraspInfo grasp;
  Pose secondary_relative;  // body pose in the secondary hand's palm frame (re-taken every frame, eq. 5)
  // A hard joint's child pushed by a hand against gravity this frame (eq. 2): the hand carries its weight,
  // so the joint integrates no gravity for the frame (see docs/design.md).
  bool supported = false;
  // Released by its hand in this step: it leaves with the hand's velocity, which the object-centred update
  // must not replace in the same step (the fingers that just let go still press it by the grip's depth).
  bool just_released = false;
  // Dynamic: Bullet had it asleep when last read, so it has not moved since (read_dynamic_bodies).
  bool read_asleep = false;
  // PushModel::Wrap: the body's poses at the ends of the last steps, over GraspSettings::velocity_window_s (a
  // HandMotionHistory of its pose; the world's velocity_window samples at most), so that the let-go reads a
  // particle's motion into the body against the body's own over the same window (moved_into). Recorded, saved and
  // hashed under Wrap only (keeps_body_paths).
  HandMotionHistory path;

  // Whether the hand in slot `hand` holds this body, as primary or secondary. (A null secondary id has
  // index 0 too, so comparing indices alone would make hand slot 0 hold every singly held body.)
  bool held_by(uint32_t hand) const {
    return grasp.grasped &&
           (grasp.primary.index == hand || (!grasp.secondary.is_null() && grasp.secondary.index == hand));
  }
};

// Not state: a body's last world box (local_box_in_world of its prepared local box), keyed by its pose and local
// box. may_lie_deeper boxes a hard child's parent for each pose the child is tried at (twice a stopped_by_parent,
// several times a held lid's step), and the parent has not moved.
struct WorldBox {
  Vec3 lo = Vec3::Zero(), hi = Vec3::Zero();
};
using WorldBoxMemo = BitMemo<13, WorldBox>;

// A body slot: its model and its state, and the slot's generation and liveness.
struct Body : BodyModel, BodyState {
  uint32_t generation = 0;
  bool alive = false;
  mutable WorldBoxMemo box_memo;  // read and written under the world's lock, as every body is

  bool manipulable() const { return alive && declared == BodyMotion::Dynamic; }
};

constexpr uint32_t kWorldParent = UINT32_MAX;

// A joint's model: what it joins and how. Hard joints keep their coordinate in the state and place the child
// from it; soft joints live in Bullet and only read back.
struct JointSlotModel {
  JointType type = JointType::Hinge;
  JointModel model = JointModel::Hard;
  JointSolver solver = JointSolver::Exact;
  uint32_t parent = kWorldParent;
  uint32_t child = 0;
  HingeFrame hinge;
  SliderFrame slider;
  BallFrame ball;
  FixedFrame fixed;
  double damping = 0;
  JointVertices vertices;  // the child's model vertices and their moments about the joint point (eq. 4)
  double length = 0;       // child size (m) that turns an axis error into a displacement
  int constraint = -1;     // soft: Bullet constraint handle
  int depth = 0;           // hard: joints between the child and the root of its group
};

struct JointSlotState {
  double value = 0, rate = 0;          // hinge / slider coordinate and its rate
  Quat rotation = Quat::Identity();    // ball
  Vec3 spin = Vec3::Zero();            // ball: angular velocity relative to the parent, world frame
  Quat solved_rotation = Quat::Identity();  // ball: the micro-simulator's last answer
  JointSolveResult last;  // the micro-simulator's solve of this step, if `solved`
  bool solved = false;

  void clear_solve() {
    last = JointSolveResult();
    solved = false;
  }
};

// Not state: a hinge child's last pose (hinge_pose, world_joints.cpp), keyed by the parent pose, the angle and the
// frame's pivots, axis and rest. A held lid is placed from the same joint value and parent several times a step
// (the pose fit, the first substep, the solve's start, its placement), each a sine and cosine and two quaternion
// products the same as the last.
using HingePoseMemo = BitMemo<21, Pose>;

struct Joint : JointSlotModel, JointSlotState {
  uint32_t generation = 0;
  bool alive = false;
  mutable HingePoseMemo hinge_memo;  // read and written under the world's lock, as every joint is
};

// A hand's model: its definition and what is built from it once.
struct HandSlotModel {
  HandDef def;
  std::shared_ptr<const HandModel> model;
  HandReach reach;  // the coarse bounds of the lazy particles (below), built once from the model
  GripBind grip_bind;  // the model's joints grip_terms reads, made once from the model
};

// Whether a world's hands keep their bones' history (HandSlotState::articulation): the squeeze rule reads it over the
// closing window, Wrap's press the closing fingers' own speed. One test, so that what records it (pose_hands) and
// what saves and hashes it (world_state.cpp) agree: a restored Wrap world whose history was not saved stepped into
// a history newer than its clock ("time: must increase").
inline bool keeps_articulation(const WorldDef& def) {
  return def.grasp.squeeze_distance > 0 || def.push_model == PushModel::Wrap;
}

// Whether a world's bodies keep their path (BodyState::path): Wrap's let-go reads it. One test for what records it
// (record_body_paths) and what saves and hashes it (world_state.cpp), as keeps_articulation is.
inline bool keeps_body_paths(const WorldDef& def) { return def.push_model == PushModel::Wrap; }

// A hand's state: the tracked frame's bones and palm, the histories the grasp rules read, and the particle
// caches (skinned from the bones, deformed from the contacts; saved so a restored world reads back the same).
struct HandSlotState {
  HandState state;
  HandMotionHistory history;
  GripHistory grip;  // grip span and palm over the last closing_window_s (GraspSettings::closing_distance)
  ArticulationHistory articulation;  // bones over the last closing_window_s, when keeps_articulation(def)
  Pose palm;
  bool has_pose = false;  // a tracked frame has been seen
  // Lazy particles: a hand whose coarse bounds (from the bones, before skinning) are far from every body skips
  // skinning its particles; state.bones are kept, and the particles are skinned when something reads them.
  bool particles_current = true;    // state.tracked_positions belong to the last tracked frame
  bool deformed_current = true;     // state.deformed_positions hold this frame's deformation (else == tracked)
  std::vector<double> group_bounds; // box of each particle group's centres (6 per group); empty: not skinned
                                    // (while reach_groups_only, only reach_groups' boxes are current)
  std::vector<uint32_t> reach_groups;  // the groups skin_particles_in_reach skinned, ascending
  bool reach_groups_only = false;      // only reach_groups have boxes (else every group has its exact box)
  std::vector<Vec3> displaced_centres;  // deformed centre of each of state.displaced (deform_hands)
};

// A hand slot: model, state, and what is rebuilt from them when needed (neither saved nor hashed).
struct HandSlot : HandSlotModel, HandSlotState {
  uint32_t generation = 0;
  bool alive = false;
  Eigen::Matrix3Xd render;
  bool render_dirty = true;
  // ParticleContacts::BulletObjects: this hand's particles as Bullet objects, rebuilt when bodies change.
  std::unique_ptr<BulletParticleCollider> bullet_particles;
  std::vector<uint32_t> bullet_bodies;  // body slot of each collider body
  uint64_t bullet_version = 0;
};

// A particle's own velocity at `point`, carried by its bone (ArticulationHistory::point_velocity over
// GraspSettings::velocity_window_s, at most velocity_window samples): how Wrap measures a finger's motion, for the
// closing finger's press and the let-go's overlap (pose_fit.cpp). Only where keeps_articulation(def).
inline Vec3 particle_velocity(const WorldDef& def, const HandSlot& hand, int particle, const Vec3& point) {
  return hand.articulation.point_velocity(*hand.model, particle, point, def.grasp.velocity_window_s,
                                          def.grasp.velocity_window);
}

// One way a held body is inside static geometry (static_stop.cpp).
struct StaticStop {
  Vec3 normal;   // push the held body along this (unit) ...
  double depth;  // ... by this much to take one of its points out
};

// How far, at most, a particle may have moved relative to its held body since the pair's anchor (below) for the
// hold path to run (contacts.cpp). 1 micrometre: far below what a hand tracker resolves (joint jitter is of the
// order of a millimetre, docs/grasp.md "Release"), so a hand this close to where it was holds the body as it did,
// and far above the rounding of a body's pose carried by its hand (1e-12 m at 10 km from the origin), so a hand
// that carries a body without moving on it stays on the hold path.
constexpr double kHoldStill = 1e-6;

// The contacts of one hand on one body in the current step, and the grasp state machine of that pair.
struct HandBodyPair {
  // A new pair: no contacts yet, its tracker under the world's grasp settings.
  explicit HandBodyPair(const GraspSettings& grasp) : tracker(grasp) {}
  GraspTracker tracker;
  std::vector<ParticleContact> contacts;
  int previous_count = 0;
  // Per touching particle (sorted by particle), the face it entered the body through: contacts of a particle
  // whose centre is inside keep that face (see keep_entry_faces). `previous_faces` is last step's list.
  std::vector<EntryFace> entry_faces, previous_faces;
  bool opposing_alone = false;  // this step: eq. 3 over this hand's contacts alone (decide_grasps)
  // PushModel::Wrap: this hand let go of this body, or its closing digits were left in the free body (forms_grip),
  // and it has touched the body in every step since (the pair ends with its contacts; a grasp clears it). Its overlap
  // then is the grip's, left by the hold or the closing, not a push: fit_touched_bodies moves the body out of it only
  // as far as the hand moves into it (docs/grasp.md "Under Wrap": the let-go; "The jump when wrapping ends").
  bool let_go = false;
  // The intent rule (GraspSettings::closing_distance > 0): the hand appeared with a particle's centre inside this body
  // (the pair began in the hand's first tracked frame: tracking began or came back, or the hand teleported) and has
  // touched the body in every step since (the pair ends with its contacts). It begins no grasp of the body, alone or
  // with another hand, until the two come apart: the tracker never showed the hand reaching the body and closing
  // onto its surface, so where it entered (the penetration directions eq. 3 opposes) was not seen, and what it does
  // inside is not a grip forming (docs/grasp.md "The appeared rule, landed").
  bool appeared_inside = false;
  // While grasped: the particles of the opposing pair found last (hand_intent tries them first), or -1. The
  // hold path (docs/grasp.md "The hold path") collides only these two while the hand holds the body still.
  std::array<int, 2> witness{-1, -1};
  // The hand's bones and the body's pose at the last full contact pass of a held pair (no bones: none): the hold
  // path runs while no particle has moved farther than kHoldStill from where it was then, relative to the body.
  std::vector<BoneTransform> anchor;
  Pose anchor_pose;
  // Not state: the anchor's bones in the frame of anchor_pose, made at holds_still's first check of the anchor,
  // so a held still body pays for them once per anchor, not per step. Emptied when the anchor is set; a restored
  // pair starts empty.
  mutable std::vector<BoneTransform> anchor_in_body;
  // This step only. `still`: pose_hands found the hand still on the held body, so the body's particles were not
  // skinned. `lazy`: `contacts` hold the witness pair alone; complete_contacts makes the full list from the
  // body's pose and velocity and the step's dt as detect_contacts saw them (contact_*), when something reads it.
  bool still = false, lazy = false;
  // While lazy: the witnesses' entry faces before hold_by_witness renewed them (in particle order), from which
  // complete_contacts puts `previous_faces` back together (the witness pass moves that list into entry_faces).
  std::array<EntryFace, 2> witness_faces_before;
  Pose contact_pose;
  BodyVelocity contact_velocity;
  double contact_dt = 0;
};

// The pairs of a world, ordered by (hand slot, body slot) so every pass over them is deterministic.
using HandBodyPairs = std::map<std::pair<uint32_t, uint32_t>, HandBodyPair>;

// The world-level model: what add_* and remove_* build and a step only reads. With the *Model half of every live
// slot of the tables below, it is what a restoring world must already have (model_fingerprint).
struct WorldModel {
  WorldDef def;
  std::vector<uint32_t> free_body_slots, free_joint_slots, free_hand_slots;  // where the next add goes
  std::vector<uint32_t> joint_order;  // live hard joints, parents before children
  uint64_t body_version = 1;  // bumped on add/remove body, so per-hand caches know to rebuild
};

// The world-level state: what a step changes and the next one reads. With the *State half of every live slot,
// it is what save_state writes and state_hash hashes (visit_world in world_state.cpp).
struct WorldState {
  double time = 0;
  double accumulator = 0;  // the part of a substep carried to the next frame
  int awake_bodies = 0;    // dynamic bodies Bullet still simulated after the last substep it ran
  HandBodyPairs pairs;
  uint64_t nonfinite_recoveries = 0;  // Bullet results replaced by the last finite state (see substep)
  uint64_t idle_substeps = 0;         // substeps in which Bullet was skipped (nothing awake)
};

// Every body slot's world bounds (world_activity.cpp), 6 doubles a slot (lo xyz, hi xyz; empty for a dead slot) in
// one flat array: derived from the poses so that the hand-body broadphase scans it instead of the bodies.
struct BodyBoxes {
  std::vector<double> body_boxes;
  mutable std::vector<uint32_t> box_order;  // sweep-and-prune order of body_boxes (sort_boxes)
  mutable std::vector<double> box_lo_x;
  mutable double widest_box_x = 0;
  mutable bool box_order_dirty = true;

  void update_box(const std::vector<Body>& bodies, uint32_t body);  // after `body` moved, was added or removed
  // The broadphase: the live bodies whose box overlaps [lo, hi] grown by `margin`, in slot order (out), or
  // only whether there is one (out null). Every body slot has its box (add_body boxes it at once).
  bool bodies_near(const Vec3& lo, const Vec3& hi, double margin, std::vector<uint32_t>* out) const;
  bool box_near_any_body(const Vec3& lo, const Vec3& hi, double margin) const;
  void sort_boxes() const;
};

// Scratch of the static stops (static_stop.cpp), kept so that a step allocates nothing once it has grown.
struct StaticStopScratch {
  std::vector<StaticStop> stops;
  std::vector<ParticleContact> contacts;
  Eigen::Matrix3Xd points, theirs;
  std::vector<std::pair<int, int>> ranges;
  std::vector<uint32_t> near;
  std::vector<ParticleContact> surfaces;  // support_contacts: a support's surfaces near the body
  std::vector<const Body*> path;          // and the bodies asked whether they bear it (bears)
};

// The id of a table's slot `index`: the index with the slot's generation now.
template <class IdT, class Slot>
IdT slot_id(const std::vector<Slot>& slots, uint32_t index) {
  return {index, slots[index].generation};
}

// This step's frame of each hand slot, indexed like the hands (null: no frame, the hand is untracked).
using SlotFrames = std::vector<const HandFrame*>;

// Scratch of the particle passes (skinning, contacts, deformation), kept so that a step allocates nothing once the
// buffers have grown. Each pass clears what it uses first.
struct ParticleScratch {
  std::vector<double> near_boxes;       // skin_particles_in_reach
  std::vector<uint32_t> near_bodies;    // the broadphase queries of skin_particles_in_reach and detect_contacts
  std::vector<EntryFace> faces;         // hold_by_witness, complete_contacts
  std::vector<ParticleContact> complete;  // hold_by_witness, complete_contacts
  std::vector<ParticleContact> contacts;  // detect_contacts, then deform_hand
  std::vector<std::pair<int, int>> ranges;  // detect_contacts, hold_by_witness, complete_contacts
  std::vector<std::pair<int, int>> inside;  // deform_hand (displace_particles)
};

// The hands' particles as the skinning, contact and deformation stages share them and the readers (World's
// particle, contact and render accessors, save_state, remove_body) complete them. A stage may leave work lazy:
// the particles of a hand far from every body are not skinned (skinning.cpp), a still held pair's contacts beyond
// its witness pair are not collided, nor the deformation made from them (the hold path, contacts.cpp); whoever
// reads them makes them here from the step's own numbers, with the same bits the stage would have made.
// Reads the world's def, bodies and their boxes; writes the hands' particle caches, the pairs' contacts and their
// hold-path flags. A view over World::Impl's tables (World::Impl::particles()), made where it is used.
struct HandParticles {
  const WorldDef& def;
  const std::vector<Body>& bodies;
  const BodyBoxes& boxes;
  std::vector<HandSlot>& hands;
  HandBodyPairs& pairs;
  ParticleScratch& scratch;
  bool hold_path;  // off: every held pair takes the full contact pass (World::Impl::hold_path)

  // Skinning (skinning.cpp): skin now, skin the groups within reach of a body, skin a still pair's witnesses,
  // bring the skipped particles (deformed: and the lazy contacts and deformation) up to date, the render mesh.
  void skin_particles(HandSlot& h);
  int skin_particles_in_reach(HandSlot& h);
  void skin_witnesses(HandSlot& h);
  void refresh_particles(HandSlot& h, bool deformed);
  bool near_any_body(const Vec3& lo, const Vec3& hi) const;
  void skin_render_mesh(HandSlot& h);
  // The hold path (contacts.cpp): whether the hand holds the pair's body still since its anchor, the witness
  // pass of a still pair, and the full contacts of a lazy pair made when read (every lazy pair of the hand,
  // then its deformation).
  bool holds_still(const HandSlot& h, const Body& b, const HandBodyPair& pair) const;
  bool hold_by_witness(uint32_t hand, uint32_t body, HandBodyPair& pair, double dt);
  void complete_contacts(uint32_t hand);
  void complete_all_contacts();
  // One hand's deformation from its contacts of the frame (deformation.cpp); the number of particles displaced.
  int deform_hand(uint32_t hand);
};

// The particle index ranges of `h` whose group box, grown by `reach`, overlaps a body's world box (contacts.cpp).
void near_particle_ranges(const HandSlot& h, double reach, const Vec3& body_lo, const Vec3& body_hi,
                          std::vector<std::pair<int, int>>& ranges);

// What moves (world_activity.cpp; the body boxes are BodyBoxes): the lists the per-step passes walk instead of every
// body, so settled and static bodies cost nothing.
struct MovingBodies {
  std::vector<uint32_t> held;      // grasped bodies; may keep entries no longer grasped (held_bodies filters)
  std::vector<uint32_t> released;  // bodies whose just_released is set
  std::vector<uint32_t> letting_go;  // hard joints' children let go of in this step, held to its end (end_grasp)
  std::vector<uint32_t> dynamic;   // live dynamic bodies, rebuilt when motion_version moves on
  // Bodies whose path holds samples (BodyState::path): those of a hand-body pair at the last step's end
  // (record_body_paths), in slot order. May name a removed body (its path was reset when the slot was filled).
  std::vector<uint32_t> pathed, pathed_next;
  uint64_t motion_version = 1, dynamic_version = 0;
};

// A body's motion now (world.cpp): Bullet's copy follows, and the dynamic list is rebuilt (motion_version).
void set_motion(BulletBackend& backend, MovingBodies& moving, Body& b, BodyMotion motion);

// Scratch of fit_touched_bodies (pose_fit.cpp), kept so that a step allocates nothing once it has grown.
struct PoseFitScratch {
  std::vector<Vec3> from, to;
  std::vector<SkinContact> pressed;  // contacts within the skin
  std::vector<SkinContact> overlap;  // the bone's overlap (PushModel::Physical)
  std::vector<CoordinatePush> levers;  // a hinge's or slider's child's overlap (overlap_step)
  std::vector<SkinContact> support;  // where a pushed body rests on static geometry (PushModel::Physical)
  StaticStopScratch stop;            // support_contacts' query of the static geometry
  std::vector<std::pair<uint32_t, uint32_t>> held_groups;  // (hand, group root) of every held body
  std::vector<std::pair<uint32_t, HandBodyPairs::value_type*>> touched;  // (body, pair) of every touching pair
};

// Scratch of decide_grasps (grasp.cpp), kept so that a step allocates nothing once it has grown.
struct GraspScratch {
  struct Intent {
    bool opposing = false;  // eq. 3 (across parts when a grasp would begin)
    bool closing = false;   // the hand closed by closing_distance within closing_window_s
  };
  std::vector<Vec3> directions;
  std::vector<int> parts;
  std::vector<Intent> intents;  // per pair in map order: eq. 3 and closing of its hand by itself
};

// The grasp bookkeeping (grasp.cpp): a grasp begins (the body attached to its hand, or a second hand joining), ends
// (the body released with its hand's velocity, or handed over to the second hand), a pair ends with its
// hand or body removed; each raises its event. Used by decide_grasps and by World's removals and set_body_pose.
// Reads the def, the hands and the body boxes; writes the bodies, the pairs, Bullet's copy, the moving lists,
// the static stops' scratch and the events. A view over World::Impl's tables (World::Impl::grasps()).
struct Grasps {
  const WorldDef& def;
  std::vector<Body>& bodies;
  const std::vector<HandSlot>& hands;
  const BodyBoxes& boxes;
  HandBodyPairs& pairs;
  BulletBackend& backend;
  MovingBodies& moving;
  StaticStopScratch& stop_scratch;  // held_pose's, in follow_hand
  std::vector<Event>& events;

  BodyId body_id(uint32_t index) const { return slot_id<BodyId>(bodies, index); }
  HandId hand_id(uint32_t index) const { return slot_id<HandId>(hands, index); }
  void begin_grasp(uint32_t hand, uint32_t body);
  // `touching`: the hand still touches the body in this frame (a hard joint's child is carried through it).
  void end_grasp(uint32_t hand, uint32_t body, EventReason reason, bool zero_velocity, bool touching = false);
  void hand_over(Body& b);
  void finish_releases();  // after the joint solve: the children let go of this step are free (letting_go)
  void release(Body& b, const BodyVelocity& velocity);
  void retake_relative_poses(Body& b);
  // Ends what a (hand, body) pair has going on before one of them is removed: GraspEnd with `reason` when
  // the hand holds the body, ContactEnd when it touched it. The caller erases the pair.
  void end_pair(uint32_t hand, uint32_t body, EventReason reason);
};

// The world: its model and state, the slot tables (each slot both halves, world_impl.h above), Bullet (a
// service that keeps its own copy, "The core owns the state" in docs/design.md), the step's output, and what
// is derived from the state to make a step cheap (world_activity.cpp) or is scratch.
struct World::Impl : WorldModel, WorldState, BodyBoxes, MovingBodies {
  std::unique_ptr<BulletBackend> backend;
  std::vector<Body> bodies;
  std::vector<Joint> joints;
  std::vector<HandSlot> hands;
  std::vector<Event> events;
  // How many of `events` (at the front) the last step raised. The next step drops those and keeps the ones
  // that removals raised after it, so a caller who reads events() after each step sees those too.
  size_t step_events = 0;
  StepReport report;  // of the last step (last_step)

  explicit Impl(const WorldDef& d);

  Body& body(BodyId id, const char* argument = "body");
  const Body& body(BodyId id, const char* argument = "body") const;
  HandSlot& hand(HandId id, const char* argument = "hand");
  const HandSlot& hand(HandId id, const char* argument = "hand") const;
  BodyId body_id(uint32_t index) const { return slot_id<BodyId>(bodies, index); }
  HandId hand_id(uint32_t index) const { return slot_id<HandId>(hands, index); }
  JointId joint_id(uint32_t index) const { return slot_id<JointId>(joints, index); }
  Joint& joint(JointId id, const char* argument = "joint");
  const Joint& joint(JointId id, const char* argument = "joint") const;

  // Joints (world_joints.cpp).
  JointId add_joint(Joint j, BodyId parent, BodyId child, const std::string& argument);
  void rebuild_joint_order();

  HandId add_hand(const HandDef& def, std::shared_ptr<const HandModel> model);
  // The hands' particles, skinned, collided and deformed lazily (HandParticles above).
  ParticleScratch particle_scratch;
  // The hold path (contacts.cpp). Off: every held pair takes the full pass (tests compare the two).
  bool hold_path = true;
  HandParticles particles() { return {def, bodies, *this, hands, pairs, particle_scratch, hold_path}; }

  // The grasp bookkeeping (Grasps above).
  StaticStopScratch stop_scratch;  // held_pose's, in follow_hand
  Grasps grasps() { return {def, bodies, hands, *this, pairs, *backend, *this, stop_scratch, events}; }

  // Algorithm 1 (world_step.cpp): its stages are free functions (below World::Impl), each defined in the file
  // named after it; each returns its work or why it had none.
  StepReport step(double dt, const SlotFrames& frames);  // Algorithm 1 (world_step.cpp)
  GraspScratch grasp_scratch;  // decide_grasps
  PoseFitScratch pose_fit_scratch;  // fit_touched_bodies

  // Step input checks (step_input.cpp): everything is checked before anything changes.
  void validate_dt(double dt) const;
  void validate_hand_frame(const HandFrame& frame, const HandSlot& h, const std::string& argument) const;
  // The step's frames by hand slot, in frames_by_id_scratch (kept so that a step allocates none; used under the
  // world's lock, by the step it is made for).
  const SlotFrames& frames_by_id(double dt, const std::vector<HandInput>& inputs) const;
  mutable SlotFrames frames_by_id_scratch;
  SlotFrames frames_by_position(double dt, const std::vector<HandFrame>& list) const;  // deprecated overload

  // Save and restore (world_state.cpp).
  std::vector<uint8_t> save_state();
  void restore_state(const uint8_t* data, size_t size, bool keep_events);
  uint64_t state_hash() const;
  uint64_t model_fingerprint() const;
  std::string inconsistency() const;
  void rebuild_backend(const BackendState& state);

  // What moves (world_activity.cpp).
  void refresh_moving_boxes();
  // Under keeps_body_paths: the pose at `time`, the end of the step, of each manipulable body a hand touches or
  // holds (in a pair); the path of a body no hand is on any more starts again (BodyState::path).
  void record_body_paths(double time);
  // A pose set from outside (set_body_pose, set_joint_value) is no motion: every body's path starts again there.
  void forget_body_paths();
  const std::vector<uint32_t>& held_bodies();
  const std::vector<uint32_t>& dynamic_bodies();
};

// Stages of Algorithm 1 as free functions (issue 21 item 2), each in the file named after it: the parameters say
// what the stage reads (const) and writes. A slot table is passed whole where the stage reads one half of a
// slot and writes the other (a joint's frames and its coordinate).

// Joints (world_joints.cpp). The body at the top of `body`'s joint chain (itself if unjointed).
uint32_t group_root(const std::vector<Body>& bodies, const std::vector<Joint>& joints, uint32_t body);
// The pose of a joint's parent (the world origin for kWorldParent), and where the
// joint's coordinate puts its child now.
Pose parent_pose(const std::vector<Body>& bodies, const Joint& j);
Pose joint_child_pose(const std::vector<Body>& bodies, const Joint& j);
// Every hard child from its parent and coordinate, parents first: the child's pose and velocity, and Bullet's copy.
void place_children(const WorldModel& model, const std::vector<Joint>& joints, std::vector<Body>& bodies,
                    BulletBackend& backend);
// place_children again when nothing it reads has changed since it last ran (no coordinate, no parent moved): the
// children's poses and velocities are what it would compute, and Bullet's copies where it put them: Bullet is told
// they stay there (keep_kinematic), which is what setting them again would tell it.
void replace_children(const WorldModel& model, const std::vector<Joint>& joints, const std::vector<Body>& bodies,
                      BulletBackend& backend);
// Tells Bullet that the idle after the coming one saves every hard child again (resave_at_next_idle): an idle
// substep that places the children is followed by one that keeps them (simulate's `placed`).
void resave_children(const WorldModel& model, const std::vector<Joint>& joints, const std::vector<Body>& bodies,
                     BulletBackend& backend);
// Whether integrate_joints moves the hard joint `j` (its child not held, the joint not fixed), and any hard joint.
bool integrates(const Joint& j, const Body& child);
bool joints_integrate(const WorldModel& model, const std::vector<Joint>& joints, const std::vector<Body>& bodies);
// Whether the parent's surface stops the hard child of `j` moving from pose `before` to `after`: a child outside
// its parent (within StaticStop's slop, 0.5 mm) is stopped at its surface as at a limit, since a real parent is a
// solid the child cannot pass, while the joint's limits alone let a lid on a -pi..pi hinge swing down through its
// base. A child already inside its parent's shape is not stopped: that shape is then not the surface that bounds
// it (a drawer sliding in a cabinet given as a solid box). Joints to the world are not stopped. (static_stop.cpp)
bool stopped_by_parent(const std::vector<Body>& bodies, const Joint& j, const Pose& before, const Pose& after);
// The deepest of the child's shape points (at `child_pose`) in `parent`, and of the parent's in the child.
double depth_in(const Body& child, const Pose& child_pose, const Body& parent);
// False when no shape point of either body can lie deeper than `depth` in the other (a bound from their world
// boxes, for boxes and hulls; always true for other shapes): depth_in is then at most `depth` without being made.
bool may_lie_deeper(const Body& child, const Pose& child_pose, const Body& parent, double depth);
// One substep of the free hard joints (not held): gravity (none for a supported child), damping, limits, the
// parent's surface.
void integrate_joints(const WorldModel& model, std::vector<Joint>& joints, const std::vector<Body>& bodies, double h);
// Eq. 2's motion of a pushed child (`simulated`, where the push would put it) projected onto its joint: the
// coordinate's rate that gets there over dt, and the solve in the joint's report.
void project_push(const WorldDef& def, const std::vector<Body>& bodies, Joint& j, const Pose& simulated, double dt);
// The rigid motion `j`'s parent gives a point of its child at `point`: the parent's angular velocity, and its linear
// velocity carried to `point` (zero for a joint to the world). A child moves by it plus its joint's own motion.
BodyVelocity parent_motion(const std::vector<Body>& bodies, const Joint& j, const Vec3& point);
// How far `point`, on the child of a hinge or slider, moves per unit of the joint's coordinate (hinge: the axis
// crossed with the point's arm from the pivot, m/rad; slider: the unit axis); zero for ball and fixed joints.
Vec3 coordinate_motion(const std::vector<Body>& bodies, const Joint& j, const Vec3& point);
// A hinge's or slider's coordinate moved by `step` and held within its limits, with no rate from it; not moved when
// its parent's surface stops the child (stopped_by_parent), as solve_grasped.
void shift_coordinate(const std::vector<Body>& bodies, Joint& j, double step);
// A grasped soft-joint child (`held`: held_bodies()) chases its primary hand with the velocity that reaches it
// in one substep h; the Bullet constraint pulls it back.
void drive_soft_children(const std::vector<uint32_t>& held, std::vector<Body>& bodies,
                         const std::vector<HandSlot>& hands, BulletBackend& backend, double h);
// The child set at once to the coordinate nearest `simulated` (no rate from it): a grasped child, and the
// physical push's displacement out of the overlap (PushModel::Physical).
void solve_grasped(const WorldDef& def, const std::vector<Body>& bodies, Joint& j, const Pose& simulated, double dt);
// Line 19 (eq. 4): a grasped hard child takes the coordinate nearest where its primary hand holds it, then
// every hard child is placed; soft joints read their coordinate back from the bodies Bullet moved. A child let go of
// in this step (`letting_go`, still grasped until Grasps::finish_releases) is carried there too, and leaves with its
// hand's motion (leave_with_hand).
StageReport solve_joints(const WorldModel& model, std::vector<Joint>& joints, std::vector<Body>& bodies,
                         const std::vector<HandSlot>& hands, BulletBackend& backend,
                         const std::vector<uint32_t>& letting_go, double dt);

// What moves (world_activity.cpp), for the dynamics stage. Whether this frame's substeps must run Bullet, and
// after a Bullet substep, the dynamic bodies (`dynamic`: dynamic_bodies()) read back with their boxes.
bool physics_needed(const WorldModel& model, const WorldState& state, const std::vector<Body>& bodies,
                    const std::vector<Joint>& joints, const BulletBackend& backend,
                    const std::vector<uint32_t>& held, const std::vector<uint32_t>& dynamic,
                    const BodyBoxes& boxes, double dt);
void read_dynamic_bodies(WorldState& state, std::vector<Body>& bodies, BulletBackend& backend,
                         const std::vector<uint32_t>& dynamic, BodyBoxes& boxes);

// Line 18 (dynamics.cpp): the frame's fixed substeps (the accumulator carries the rest; the step's report gets
// the substeps, whether Bullet ran and a dropped backlog). Each glides the held bodies (`held`: held_bodies())
// towards their hand, drives the soft-joint children, runs Bullet (or idles it when nothing dynamic can move)
// and reads the dynamic bodies (`dynamic`: dynamic_bodies()) back, then integrates and places the hard joints.
StageReport simulate(const WorldModel& model, WorldState& state, std::vector<Body>& bodies, std::vector<Joint>& joints,
                     const std::vector<HandSlot>& hands, BulletBackend& backend, const std::vector<uint32_t>& held,
                     const std::vector<uint32_t>& dynamic, BodyBoxes& boxes, StepReport& report, double dt);

// Line 17 (pose_fit.cpp, eq. 2): each touched free body that no hand holds (nor a part of its joint group: `held`,
// held_bodies()) moves out of the hands: by the fitted rigid motion (PushModel::Fitted) or the pulp's impulses and
// the overlap's displacement (Physical; a body resting on static geometry, found through `boxes`, is held by its
// support instead), as a velocity for the frame written to Bullet, or along its joint (project_push); the bodies
// released this step (`released`) are done with after it. Under Wrap a pair whose closing digits it left in a free
// body is marked let go (HandBodyPair::let_go).
StageReport fit_touched_bodies(const WorldModel& model, std::vector<Body>& bodies, std::vector<Joint>& joints,
                               const std::vector<HandSlot>& hands, HandBodyPairs& pairs,
                               const std::vector<uint32_t>& held, std::vector<uint32_t>& released,
                               BulletBackend& backend, const BodyBoxes& boxes, PoseFitScratch& scratch, double dt);

// A held body stopped by static geometry (static_stop.cpp): where `b` is this frame (palm * T_rel of its primary
// hand pushed out of the ground and the static bodies; T_rel re-taken when the grip slips), with the push in
// `pushed`. `b` is one of `bodies`, whose static ones it reads through the broadphase.
Pose held_pose(const WorldDef& def, const std::vector<Body>& bodies, const BodyBoxes& boxes,
               const std::vector<HandSlot>& hands, StaticStopScratch& scratch, Body& b, Vec3* pushed = nullptr);
// Every way `held` at `pose` is inside static geometry, the ground and the bodies of mass 0: a direction to push it
// and how deep it is in (`out`). held_pose pushes it out of those deeper than StaticStop's slop (0.5 mm).
void static_stops(const WorldDef& def, const std::vector<Body>& bodies, const BodyBoxes& boxes,
                  StaticStopScratch& scratch, const Body& held, const Pose& pose, std::vector<StaticStop>& out);
// False when `held` at `pose` cannot be deeper than the slop in static geometry (a bound from its world box):
// static_stops would find only stops within the slop, which push nothing.
bool may_meet_static(const WorldDef& def, const std::vector<Body>& bodies, const BodyBoxes& boxes,
                     StaticStopScratch& scratch, const Body& held, const Pose& pose);
// Where `b` rests on static geometry (within 1 mm of the ground or a body of mass 0): contacts for skin_press that
// push the body out of the support and never pull, unbounded, hand_velocity zero (the support does not move), with
// the two surfaces' combined friction (PushModel::Physical: the support bears the hand's press).
void support_contacts(const WorldDef& def, const std::vector<Body>& bodies, const BodyBoxes& boxes,
                      StaticStopScratch& scratch, const Body& b, std::vector<SkinContact>& out);

// Grasps (grasp.cpp). Lines 10, 14, run before the contacts: each held free body (`held`: held_bodies()) goes where
// its primary hand holds it this frame (follow_hand), so the hand's contacts see the body where the hand carries it
// (docs/grasp.md "The hold path"); joint children are left to their joint. A body grasped or handed over later in
// the step follows its new hand there (Grasps::begin_grasp, hand_over).
StageReport follow_primary_hands(const WorldDef& def, const std::vector<uint32_t>& held, std::vector<Body>& bodies,
                                 const std::vector<HandSlot>& hands, const BodyBoxes& boxes, StaticStopScratch& scratch);
// A held free body where its primary hand holds it now (held_pose: palm * T_rel, stopped by static geometry), with
// that point's velocity.
void follow_hand(const WorldDef& def, std::vector<Body>& bodies, const std::vector<HandSlot>& hands,
                 const BodyBoxes& boxes, StaticStopScratch& scratch, Body& b);
// Line 20 (eq. 5): each held body (`held`, held_bodies()) that a second hand holds re-takes
// its pose in that hand's palm frame, so the secondary hand slips along the body instead of dragging it.
StageReport retake_secondary_hands(const std::vector<uint32_t>& held, std::vector<Body>& bodies,
                                   const std::vector<HandSlot>& hands);

// The frame's input (skinning.cpp): each tracked hand's bones and palm from its frame (`frames`, indexed like the
// hands; null: untracked) and the histories they feed, pushed at the frame's end time (`time` + dt). A palm that
// moved faster than the speed cap raises HandTeleported in `report`.
void track_hands(HandParticles& particles, const SlotFrames& frames, double time, StepReport& report, double dt);
// Lines 1-2 (skinning.cpp): each tracked hand's particles skinned (eq. 1) from its bones where they can touch a body
// (the paper: all), and the still held pairs marked for the hold path.
StageReport pose_hands(HandParticles& particles);
// Line 3 (contacts.cpp): each tracked hand's particles against the bodies near it, into the pairs (a pair made for
// a first contact; a held body's contacts within release_distance), with their entry faces; a still held pair
// takes the witness pass (the hold path) and becomes lazy. The paper's narrow phase (BulletObjects) rebuilds a
// hand's Bullet particles when `body_version` (WorldModel) moved on.
StageReport detect_contacts(HandParticles& particles, uint64_t body_version, double dt);
// Deformation (deformation.cpp): each tracked hand's particles inside a body move back to its surface (a still
// held pair's with its witnesses only until complete_contacts redoes it).
StageReport deform_hands(HandParticles& particles);
// Lines 4-9, 11-13, 16 (grasp.cpp): per pair, the contact events, then eq. 3 (with the closing rule, and across two
// hands on one body) fed to the pair's tracker, whose decisions begin and end grasps (Grasps); pairs with nothing
// going on are forgotten.
StageReport decide_grasps(Grasps& grasps, GraspScratch& scratch, double dt);

// What a stage returns: its work, or why it had none.
inline StageReport stage_work(int work, int particles = 0) {
  StageReport r;
  r.work = work;
  r.particles = particles;
  return r;
}
inline StageReport stage_skipped(SkipReason why) {
  StageReport r;
  r.skip = why;
  return r;
}

// A generation no other slot of any world in this process has had (world.cpp).
uint32_t fresh_generation();

// validate_frame's conditions without building argument names (hand_skeleton.cpp): the step checks every frame
// with it and calls validate_frame, which names what is wrong, only when it fails.
// Four joints at a time where the CPU has AVX2 (the same answer as joints_are_good, one joint at a time).
bool frame_is_valid(const HandFrame& frame);
bool joints_are_good(const HandFrame& frame);  // every valid joint passes validate_frame's checks

// Slot tables with generations, shared by bodies, joints and hands.
inline std::string stale_message(uint32_t index, uint32_t generation) {
  return "names no live object (removed, or from another world): index " + std::to_string(index) +
         ", generation " + std::to_string(generation);
}

template <class Slot, class IdT>
bool live_slot(const std::vector<Slot>& slots, IdT id) {
  return !id.is_null() && id.index < slots.size() && slots[id.index].generation == id.generation &&
         slots[id.index].alive;
}

template <class Slot, class IdT>
Slot& checked_slot(std::vector<Slot>& slots, IdT id, const char* argument) {
  if (live_slot(slots, id)) return slots[id.index];
  if (id.is_null()) validate::fail(argument, "is the null id", Status::StaleId);
  validate::fail(argument, stale_message(id.index, id.generation), Status::StaleId);
}

// Takes a free slot or appends one; returns its index.
template <class Slot>
uint32_t allocate_slot(std::vector<Slot>& slots, std::vector<uint32_t>& free_slots) {
  uint32_t index;
  if (!free_slots.empty()) {
    index = free_slots.back();
    free_slots.pop_back();
  } else {
    slots.emplace_back();
    index = uint32_t(slots.size() - 1);
  }
  slots[index].generation = fresh_generation();
  return index;
}

template <class Slot>
void release_slot(std::vector<Slot>& slots, std::vector<uint32_t>& free_slots, uint32_t index) {
  // The old generation stays until the slot is taken again, so the old id stays stale in the meantime.
  const uint32_t generation = slots[index].generation;
  slots[index] = Slot();
  slots[index].generation = generation;
  free_slots.push_back(index);
}


}  // namespace handsim
