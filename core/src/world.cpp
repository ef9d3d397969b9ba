#include "handsim/world.h"

#include "bullet_backend.h"
#include "state_hash.h"
#include "validate.h"

#include <cmath>

namespace handsim {
namespace {

// Generations carry a per-world salt in their top 12 bits, so an id from another world is rejected (with
// probability 4095/4096) instead of silently naming a body here; the low 20 bits count reuses of a slot.
constexpr uint32_t kGenerationBits = 20;
constexpr uint32_t kGenerationMask = (1u << kGenerationBits) - 1;

uint32_t world_salt(const void* impl) {
  uint64_t x = reinterpret_cast<uintptr_t>(impl);
  x ^= x >> 33;
  x *= 0xff51afd7ed558ccdull;
  x ^= x >> 33;
  return uint32_t(x % 4095) + 1;
}

uint32_t next_generation(uint32_t generation) {
  uint32_t count = (generation & kGenerationMask) + 1;
  if (count > kGenerationMask) count = 1;  // wrap-around; 0 would make the null id
  return (generation & ~kGenerationMask) | count;
}

struct Body {
  uint32_t generation = 0;
  bool alive = false;
  ShapeDef shape;
  double mass = 0;
  BodyMotion motion = BodyMotion::Static;
  Pose pose;
  Pose synced_pose;  // kinematic bodies: the pose Bullet last saw, for interpolating across substeps
  Vec3 linear = Vec3::Zero();
  Vec3 angular = Vec3::Zero();
  int backend = -1;
};

BodyMotion motion_of(const BodyDef& def) {
  if (def.kinematic) return BodyMotion::Kinematic;
  return def.mass > 0 ? BodyMotion::Dynamic : BodyMotion::Static;
}

void validate_world_def(const WorldDef& def) {
  validate::finite(def.gravity, "world.gravity");
  validate::positive(def.fixed_substep, "world.fixed_substep");
  if (def.max_substeps < 1 || def.max_substeps > 1000)
    validate::fail("world.max_substeps", "must be in 1..1000, got " + std::to_string(def.max_substeps));
  validate::finite(def.ground_height, "world.ground_height");
  validate::non_negative(def.ground_friction, "world.ground_friction");
}

// Checks everything about a BodyDef and returns it with its quaternion normalized.
BodyDef validated(const BodyDef& in) {
  BodyDef def = in;
  validate_shape(def.shape, "body.shape");
  validate::non_negative(def.mass, "body.mass");
  def.pose = validate::pose(def.pose, "body.pose");
  validate::finite(def.linear_velocity, "body.linear_velocity");
  validate::finite(def.angular_velocity, "body.angular_velocity");
  validate::non_negative(def.friction, "body.friction");
  validate::non_negative(def.restitution, "body.restitution");
  if (def.shape.type == ShapeType::TriangleMesh && def.mass > 0 && !def.kinematic)
    validate::fail("body.mass", "a triangle mesh body must be static (mass 0) or kinematic");
  return def;
}

}  // namespace

struct World::Impl {
  WorldDef def;
  std::unique_ptr<BulletBackend> backend;
  std::vector<Body> bodies;
  std::vector<uint32_t> free_slots;
  double time = 0;
  double accumulator = 0;
  const uint32_t salt = world_salt(this);

  explicit Impl(const WorldDef& d) : def(d), backend(std::make_unique<BulletBackend>(d)) {}

  Body& body(BodyId id, const char* argument = "body") {
    if (id.is_null())
      validate::fail(argument, "is the null id", Status::StaleId);
    if (id.index >= bodies.size() || bodies[id.index].generation != id.generation ||
        !bodies[id.index].alive)
      validate::fail(argument,
                     "names no live body (removed, or from another world): index " +
                         std::to_string(id.index) + ", generation " + std::to_string(id.generation),
                     Status::StaleId);
    return bodies[id.index];
  }

  void substep(double h) {
    for (Body& b : bodies)
      if (b.alive && b.motion == BodyMotion::Kinematic) backend->move_kinematic(b.backend, b.pose);
    backend->step(h);
    for (Body& b : bodies) {
      if (!b.alive || b.motion != BodyMotion::Dynamic) continue;
      backend->read(b.backend, b.pose, b.linear, b.angular);
    }
  }
};

World::World(const WorldDef& def) {
  validate_world_def(def);
  impl_ = std::make_unique<Impl>(def);
}
World::~World() = default;
World::World(World&&) noexcept = default;
World& World::operator=(World&&) noexcept = default;

const WorldDef& World::def() const { return impl_->def; }

void World::reset() { impl_ = std::make_unique<Impl>(impl_->def); }

BodyId World::add_body(const BodyDef& in) {
  BodyDef def = validated(in);
  Impl& w = *impl_;
  uint32_t index;
  if (!w.free_slots.empty()) {
    index = w.free_slots.back();
    w.free_slots.pop_back();
  } else {
    index = uint32_t(w.bodies.size());
    w.bodies.emplace_back();
    w.bodies.back().generation = (w.salt << kGenerationBits) | 1;
  }
  Body& b = w.bodies[index];
  b.alive = true;
  b.shape = def.shape;
  b.mass = def.mass;
  b.motion = motion_of(def);
  b.pose = b.synced_pose = def.pose;
  b.linear = b.motion == BodyMotion::Static ? Vec3::Zero() : def.linear_velocity;
  b.angular = b.motion == BodyMotion::Static ? Vec3::Zero() : def.angular_velocity;
  b.backend = w.backend->add(def, b.motion);
  return {index, b.generation};
}

void World::remove_body(BodyId id) {
  Body& b = impl_->body(id);
  impl_->backend->remove(b.backend);
  const uint32_t generation = next_generation(b.generation);
  b = Body();
  b.generation = generation;
  impl_->free_slots.push_back(id.index);
}

bool World::contains(BodyId id) const {
  return !id.is_null() && id.index < impl_->bodies.size() &&
         impl_->bodies[id.index].alive && impl_->bodies[id.index].generation == id.generation;
}

std::vector<BodyId> World::bodies() const {
  std::vector<BodyId> out;
  for (uint32_t i = 0; i < impl_->bodies.size(); ++i)
    if (impl_->bodies[i].alive) out.push_back({i, impl_->bodies[i].generation});
  return out;
}

const ShapeDef& World::body_shape(BodyId id) const { return impl_->body(id).shape; }
double World::body_mass(BodyId id) const { return impl_->body(id).mass; }
BodyMotion World::body_motion(BodyId id) const { return impl_->body(id).motion; }
Pose World::body_pose(BodyId id) const { return impl_->body(id).pose; }
Vec3 World::body_linear_velocity(BodyId id) const { return impl_->body(id).linear; }
Vec3 World::body_angular_velocity(BodyId id) const { return impl_->body(id).angular; }

void World::set_body_pose(BodyId id, const Pose& pose) {
  Body& b = impl_->body(id);
  Pose p = validate::pose(pose, "pose");
  b.pose = b.synced_pose = p;
  impl_->backend->write(b.backend, p, b.linear, b.angular);
}

void World::set_body_velocity(BodyId id, const Vec3& linear, const Vec3& angular) {
  Body& b = impl_->body(id);
  validate::finite(linear, "linear");
  validate::finite(angular, "angular");
  if (b.motion == BodyMotion::Static)
    validate::fail("body", "a static body cannot have a velocity", Status::InvalidState);
  b.linear = linear;
  b.angular = angular;
  impl_->backend->write(b.backend, b.pose, linear, angular);
}

void World::step(double dt) {
  validate::time_step(dt);
  Impl& w = *impl_;
  const double h = w.def.fixed_substep;
  w.accumulator += dt;
  // The small tolerance keeps dt = 4h from yielding 3 substeps through rounding.
  int n = int(std::floor(w.accumulator / h + 1e-9));
  if (n > w.def.max_substeps) {
    n = w.def.max_substeps;
    w.accumulator = n * h;  // drop what cannot be caught up
  }
  for (int i = 0; i < n; ++i) w.substep(h);
  w.accumulator = std::max(0.0, w.accumulator - n * h);
  w.time += dt;
}

double World::time() const { return impl_->time; }

uint64_t World::state_hash() const {
  StateHasher hasher;
  hasher.add(impl_->time);
  for (uint32_t i = 0; i < impl_->bodies.size(); ++i) {
    const Body& b = impl_->bodies[i];
    // Generations are left out: they carry the world's address-derived salt, not state.
    hasher.add(uint64_t(i) << 1 | uint64_t(b.alive));
    if (!b.alive) continue;
    hasher.add(b.pose);
    hasher.add(b.linear);
    hasher.add(b.angular);
  }
  return hasher.value();
}

}  // namespace handsim
