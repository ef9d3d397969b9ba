#include "handsim/world.h"

#include "validate.h"
#include "world_impl.h"

#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstdio>
#include <memory>
#include <mutex>
#include <vector>

namespace handsim {
namespace {

// Every generation in the process comes from one counter, so a (slot, generation) pair names at most one
// object of one world: an id from another world, live or destroyed, or from an earlier tenant of the slot
// is refused until 2^32 - 1 objects have been created in the process (see docs/design.md "Ids").
std::atomic<uint32_t> g_generation{0};

bool same_hand_def(const HandDef& a, const HandDef& b) {
  // every field of HandDef (a field added there must be added here)
  return a.handedness == b.handedness && a.particle_count == b.particle_count && a.sampling == b.sampling &&
         a.seed == b.seed && a.particle_radius == b.particle_radius && a.render_vertices == b.render_vertices;
}

// Building the procedural hand (mesh, skin groups, particles) takes ~0.2 s and depends only on the HandDef, and
// a built model is immutable, so worlds alive at the same time share the model of an equal definition. Tools
// that build many short-lived worlds (the intent judge: one per placement) spent most of their time here. Only
// weak references are kept: a model is freed with the last world using it, as before.
std::shared_ptr<const HandModel> shared_hand_model(const HandDef& def) {
  static std::mutex mutex;
  static std::vector<std::pair<HandDef, std::weak_ptr<const HandModel>>> live;
  std::lock_guard<std::mutex> lock(mutex);
  live.erase(std::remove_if(live.begin(), live.end(), [](const auto& e) { return e.second.expired(); }),
             live.end());
  for (const auto& [d, model] : live)
    if (same_hand_def(d, def))
      if (auto shared = model.lock()) return shared;
  auto model = std::make_shared<const HandModel>(build_hand_model(def));
  live.emplace_back(def, model);
  return model;
}

BodyMotion motion_of(const BodyDef& def) {
  if (def.kinematic) return BodyMotion::Kinematic;
  return def.mass > 0 ? BodyMotion::Dynamic : BodyMotion::Static;
}

void validate_world_def(const WorldDef& def) {
  validate::finite(def.gravity, "world.gravity");
  if (!(def.gravity.norm() <= validate::kMaxGravity))
    validate::fail("world.gravity", "must be at most " + validate::fmt(validate::kMaxGravity) +
                                        " m/s^2 in magnitude, got " + validate::fmt(def.gravity));
  // 1 us .. 1 s: finer than any physics rate, coarser than any frame.
  validate::in_range(def.fixed_substep, 1e-6, 1, "world.fixed_substep", "s");
  if (def.max_substeps < 1 || def.max_substeps > 1000)
    validate::fail("world.max_substeps", "must be in 1..1000, got " + std::to_string(def.max_substeps));
  validate::in_range(def.ground_height, -validate::kMaxCoordinate, validate::kMaxCoordinate, "world.ground_height", "m");
  validate::friction(def.ground_friction, "world.ground_friction");
  if (def.solver_iterations < 1 || def.solver_iterations > 10000)
    validate::fail("world.solver_iterations", "must be in 1..10000, got " + std::to_string(def.solver_iterations));
  if (def.joint_max_iterations < 1 || def.joint_max_iterations > 10000)
    validate::fail("world.joint_max_iterations",
                   "must be in 1..10000, got " + std::to_string(def.joint_max_iterations));
  validate_grasp_settings(def.grasp, "world.grasp.");
  if (def.render_threads < 1 || def.render_threads > 64)
    validate::fail("world.render_threads", "must be in 1..64, got " + std::to_string(def.render_threads));
  // A skin thicker than a finger is no finger pulp; above 1 MPa skin is crushed, not pressed.
  validate::in_range(def.skin_depth, 0, 0.05, "world.skin_depth", "m");
  validate::in_range(def.skin_pressure, 0, 1e6, "world.skin_pressure", "Pa");
  if (int(def.particle_contacts) < 0 || int(def.particle_contacts) > 1)
    validate::fail("world.particle_contacts", "unknown method " + std::to_string(int(def.particle_contacts)));
  if (int(def.push_model) < 0 || int(def.push_model) > int(PushModel::Wrap))
    validate::fail("world.push_model", "unknown model " + std::to_string(int(def.push_model)));
}

// Checks everything about a BodyDef and returns it with its quaternion normalized.
BodyDef validated(const BodyDef& in) {
  BodyDef def = in;
  validate_shape(def.shape, "body.shape");
  validate::mass(def.mass, "body.mass");
  def.pose = validate::body_pose(def.pose, "body.pose");
  validate::velocity(def.linear_velocity, "body.linear_velocity");
  validate::velocity(def.angular_velocity, "body.angular_velocity");
  validate::friction(def.friction, "body.friction");
  // Above 1 a bounce returns more energy than the impact took (2.0 threw a 1 m drop to 16.75 m).
  validate::in_range(def.restitution, 0, 1, "body.restitution", "");
  if (def.shape.type == ShapeType::TriangleMesh && def.mass > 0 && !def.kinematic)
    validate::fail("body.mass", "a triangle mesh body must be static (mass 0) or kinematic");
  return def;
}

}  // namespace

uint32_t fresh_generation() {
  uint32_t g = g_generation.fetch_add(1, std::memory_order_relaxed) + 1;
  while (g == 0) g = g_generation.fetch_add(1, std::memory_order_relaxed) + 1;  // 0 is the null id
  return g;
}

World::Impl::Impl(const WorldDef& d) : WorldModel{d}, backend(std::make_unique<BulletBackend>(d)) {}

Body& World::Impl::body(BodyId id, const char* argument) { return checked_slot(bodies, id, argument); }
const Body& World::Impl::body(BodyId id, const char* argument) const {
  return checked_slot(const_cast<std::vector<Body>&>(bodies), id, argument);
}
HandSlot& World::Impl::hand(HandId id, const char* argument) { return checked_slot(hands, id, argument); }
const HandSlot& World::Impl::hand(HandId id, const char* argument) const {
  return checked_slot(const_cast<std::vector<HandSlot>&>(hands), id, argument);
}

World::World(const WorldDef& def) {
  validate_world_def(def);
  impl_ = std::make_unique<Impl>(def);
  mutex_ = std::make_unique<std::mutex>();
}
World::~World() = default;
World::World(World&&) noexcept = default;
World& World::operator=(World&&) noexcept = default;

WorldDef World::def() const {
  const auto held = lock();
  return impl_->def;
}

void World::reset() {
  const auto held = lock();
  Impl& old = *impl_;
  // End every grasp and contact first, so a caller who follows events() sees each one close.
  Grasps grasps = old.grasps();
  for (const auto& [key, pair] : old.pairs) grasps.end_pair(key.first, key.second, EventReason::BodyRemoved);
  // They stay listed through the next step, as remove_body's do; the last step's own events stay until then too.
  std::vector<Event> events = std::move(old.events);
  const size_t step_events = old.step_events;
  impl_ = std::make_unique<Impl>(old.def);
  impl_->events = std::move(events);
  impl_->step_events = step_events;
}

BodyId World::add_body(const BodyDef& in) {
  const auto held = lock();
  BodyDef def = validated(in);
  PreparedShape prepared = prepare_shape(def.shape, "body.shape");
  Impl& w = *impl_;
  const uint32_t index = allocate_slot(w.bodies, w.free_body_slots);
  Body& b = w.bodies[index];
  b.alive = true;
  b.shape = def.shape;
  b.prepared = std::move(prepared);
  b.mass = def.mass;
  b.friction = def.friction;
  b.restitution = def.restitution;
  b.declared = b.motion = motion_of(def);
  b.pose = b.synced_pose = def.pose;
  b.linear = b.motion == BodyMotion::Static ? Vec3::Zero() : def.linear_velocity;
  b.angular = b.motion == BodyMotion::Static ? Vec3::Zero() : def.angular_velocity;
  b.unit_inertia = shape_unit_inertia(def.shape);
  b.path = HandMotionHistory(w.def.grasp.velocity_window, w.def.grasp.velocity_window_s);
  b.backend = w.backend->add(def, b.motion);
  ++w.body_version;
  ++w.motion_version;
  w.update_box(w.bodies, index);
  return {index, b.generation};
}

void World::remove_body(BodyId id) {
  const auto held = lock();
  Impl& w = *impl_;
  Body& b = w.body(id);
  for (const Joint& j : w.joints)
    if (j.alive && (j.child == id.index || j.parent == id.index))
      validate::fail("body", "a joint still uses it; remove the joint first", Status::InvalidState);
  w.particles().complete_all_contacts();  // the hands' deformation of the last step, with this body's contacts, stays readable
  // Let go of it first, so the hands' grasp state and the events stay consistent: every hand holding it
  // gets a GraspEnd, every hand touching it a ContactEnd, and no pair keeps the slot index it leaves behind.
  for (auto it = w.pairs.begin(); it != w.pairs.end();) {
    if (it->first.second != id.index) {
      ++it;
      continue;
    }
    w.grasps().end_pair(it->first.first, id.index, EventReason::BodyRemoved);
    it = w.pairs.erase(it);
  }
  w.backend->remove(b.backend);
  release_slot(w.bodies, w.free_body_slots, id.index);
  ++w.body_version;
  ++w.motion_version;
  w.update_box(w.bodies, id.index);
}

bool World::contains(BodyId id) const {
  const auto held = lock();
  return !id.is_null() && id.index < impl_->bodies.size() &&
         impl_->bodies[id.index].alive && impl_->bodies[id.index].generation == id.generation;
}

bool World::contains(HandId id) const {
  const auto held = lock();
  return !id.is_null() && id.index < impl_->hands.size() && impl_->hands[id.index].alive &&
         impl_->hands[id.index].generation == id.generation;
}

std::vector<BodyId> World::bodies() const {
  const auto held = lock();
  std::vector<BodyId> out;
  for (uint32_t i = 0; i < impl_->bodies.size(); ++i)
    if (impl_->bodies[i].alive) out.push_back({i, impl_->bodies[i].generation});
  return out;
}

ShapeDef World::body_shape(BodyId id) const {
  const auto held = lock();
  return impl_->body(id).shape;
}
double World::body_mass(BodyId id) const {
  const auto held = lock();
  return impl_->body(id).mass;
}
BodyMotion World::body_motion(BodyId id) const {
  const auto held = lock();
  return impl_->body(id).motion;
}
GraspInfo World::body_grasp(BodyId id) const {
  const auto held = lock();
  return impl_->body(id).grasp;
}

int World::body_contact_count(BodyId body, HandId hand) const {
  const auto held = lock();
  impl_->body(body);
  impl_->hand(hand);
  impl_->particles().complete_contacts(hand.index);  // a held body's contacts beyond its witness pair are made when read
  auto it = impl_->pairs.find({hand.index, body.index});
  return it == impl_->pairs.end() ? 0 : int(it->second.contacts.size());
}

std::vector<ParticleContact> World::body_contacts(BodyId body, HandId hand) const {
  const auto held = lock();
  impl_->body(body);
  impl_->hand(hand);
  impl_->particles().complete_contacts(hand.index);
  auto it = impl_->pairs.find({hand.index, body.index});
  return it == impl_->pairs.end() ? std::vector<ParticleContact>() : it->second.contacts;
}

std::vector<Event> World::events() const {
  const auto held = lock();
  return impl_->events;
}
StepReport World::last_step() const {
  const auto held = lock();
  return impl_->report;
}

std::string World::stage_summary() const {
  const auto held = lock();
  return summary(impl_->report);
}

// --- hands ---

// The model is built (or found shared) before the lock: it is the expensive part and touches nothing of the
// world's.
HandId World::add_hand(const HandDef& def) {
  auto model = shared_hand_model(def);
  const auto held = lock();
  return impl_->add_hand(def, std::move(model));
}

HandId World::add_hand(const HandDef& def, const SkinnedMesh& mesh, const HandFrame& bind) {
  auto model = std::make_shared<const HandModel>(build_hand_model(def, mesh, bind));
  const auto held = lock();
  return impl_->add_hand(def, std::move(model));
}

HandId World::Impl::add_hand(const HandDef& def, std::shared_ptr<const HandModel> model) {
  const uint32_t index = allocate_slot(hands, free_hand_slots);
  HandSlot& h = hands[index];
  h.alive = true;
  h.def = def;
  h.model = std::move(model);
  h.history = HandMotionHistory(this->def.grasp.velocity_window, this->def.grasp.velocity_window_s);
  h.state.tracked = false;
  h.state.tracked_positions = h.model->particle_bind;
  h.state.deformed_positions = h.model->particle_bind;
  h.reach = build_hand_reach(*h.model);
  h.grip_bind = grip_bind(*h.model);
  h.particles_current = h.deformed_current = true;
  return {index, h.generation};
}

void World::remove_hand(HandId id) {
  const auto held = lock();
  Impl& w = *impl_;
  w.hand(id);
  for (auto it = w.pairs.begin(); it != w.pairs.end();) {
    if (it->first.first != id.index) {
      ++it;
      continue;
    }
    // A body it held alone falls at rest; one it shared stays with the other hand.
    w.grasps().end_pair(id.index, it->first.second, EventReason::HandRemoved);
    it = w.pairs.erase(it);
  }
  release_slot(w.hands, w.free_hand_slots, id.index);
}

std::vector<HandId> World::hands() const {
  const auto held = lock();
  std::vector<HandId> out;
  for (uint32_t i = 0; i < impl_->hands.size(); ++i)
    if (impl_->hands[i].alive) out.push_back(impl_->hand_id(i));
  return out;
}

const HandModel& World::hand_model(HandId id) const {
  const auto held = lock();
  return *impl_->hand(id).model;
}
bool World::hand_tracked(HandId id) const {
  const auto held = lock();
  return impl_->hand(id).state.tracked;
}
Pose World::hand_palm_pose(HandId id) const {
  const auto held = lock();
  return impl_->hand(id).palm;
}

// Logically const: a hand far from every body skipped skinning its particles in the step, and reading them
// here fills that cache (the pimpl pointer lets a const accessor update it).
Eigen::Matrix3Xd World::hand_particles(HandId id, bool deformed) const {
  const auto held = lock();
  HandSlot& h = impl_->hand(id);
  impl_->particles().refresh_particles(h, deformed);
  return deformed ? h.state.deformed_positions : h.state.tracked_positions;
}

Eigen::Matrix3Xd World::hand_render_vertices(HandId id) {
  const auto held = lock();
  HandSlot& h = impl_->hand(id);
  if (h.render_dirty) impl_->particles().skin_render_mesh(h);
  return h.render;
}
Pose World::body_pose(BodyId id) const {
  const auto held = lock();
  return impl_->body(id).pose;
}
Vec3 World::body_linear_velocity(BodyId id) const {
  const auto held = lock();
  return impl_->body(id).linear;
}
Vec3 World::body_angular_velocity(BodyId id) const {
  const auto held = lock();
  return impl_->body(id).angular;
}

void World::set_body_pose(BodyId id, const Pose& pose) {
  const auto held = lock();
  Body& b = impl_->body(id);
  Pose p = validate::body_pose(pose, "pose");
  if (b.jointed())
    validate::fail("body", "is the child of a hard joint; move its parent or set the joint value",
                   Status::InvalidState);
  b.pose = b.synced_pose = p;
  // Without this the attach stage would put a held body straight back into the hand.
  impl_->grasps().retake_relative_poses(b);
  impl_->backend->write(b.backend, p, b.linear, b.angular);
  impl_->update_box(impl_->bodies, id.index);
  if (!impl_->joint_order.empty()) place_children(*impl_, impl_->joints, impl_->bodies, *impl_->backend);
  impl_->refresh_moving_boxes();
  impl_->forget_body_paths();
}

void World::set_body_velocity(BodyId id, const Vec3& linear, const Vec3& angular) {
  const auto held = lock();
  Body& b = impl_->body(id);
  validate::velocity(linear, "linear");
  validate::velocity(angular, "angular");
  if (b.motion == BodyMotion::Static)
    validate::fail("body", "a static body cannot have a velocity", Status::InvalidState);
  if (b.jointed())
    validate::fail("body", "is the child of a hard joint; its velocity comes from the joint", Status::InvalidState);
  b.linear = linear;
  b.angular = angular;
  impl_->backend->write(b.backend, b.pose, linear, angular);
}

StepReport World::step(double dt) { return step(dt, std::vector<HandInput>()); }  // locks there

double World::time() const {
  const auto held = lock();
  return impl_->time;
}

void set_motion(BulletBackend& backend, MovingBodies& moving, Body& b, BodyMotion motion) {
  if (b.motion == motion) return;
  backend.set_motion(b.backend, motion, b.mass);
  b.motion = motion;
  b.read_asleep = false;
  ++moving.motion_version;
  b.synced_pose = b.pose;
  backend.write(b.backend, b.pose, b.linear, b.angular);
}

}  // namespace handsim
