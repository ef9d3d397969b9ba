// The only file of the world that includes Bullet (bullet_particles.cpp, the paper-mode particle
// baseline, is the other Bullet user).
#include "bullet_backend.h"

#include <btBulletDynamicsCommon.h>
#include <BulletCollision/CollisionShapes/btConvexHullShape.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <vector>

namespace handsim {
namespace {

btVector3 bt(const Vec3& v) { return btVector3(v.x(), v.y(), v.z()); }
Vec3 from_bt(const btVector3& v) { return Vec3(v.x(), v.y(), v.z()); }

btTransform bt(const Pose& p) {
  const Quat& q = p.orientation;
  return btTransform(btQuaternion(q.x(), q.y(), q.z(), q.w()), bt(p.position));
}

Pose from_bt(const btTransform& t) {
  btQuaternion q = t.getRotation();
  return {from_bt(t.getOrigin()), Quat(q.w(), q.x(), q.y(), q.z()).normalized()};
}

// Bullet shapes keep pointers into their vertex/index arrays, so a triangle mesh owns its arrays here.
struct MeshStorage {
  std::vector<btScalar> vertices;
  std::vector<int> indices;
  std::unique_ptr<btTriangleIndexVertexArray> array;
};

std::unique_ptr<btCollisionShape> make_raw_shape(const ShapeDef& s, std::unique_ptr<MeshStorage>& mesh) {
  switch (s.type) {
    case ShapeType::Box:
      return std::make_unique<btBoxShape>(bt(s.half_extents));
    case ShapeType::Sphere:
      return std::make_unique<btSphereShape>(s.radius);
    case ShapeType::Capsule:
      return std::make_unique<btCapsuleShape>(s.radius, 2 * s.half_height);
    case ShapeType::ConvexHull: {
      auto hull = std::make_unique<btConvexHullShape>();
      for (const Vec3& p : s.points) hull->addPoint(bt(p), false);
      hull->recalcLocalAabb();
      return hull;
    }
    case ShapeType::TriangleMesh: {
      mesh = std::make_unique<MeshStorage>();
      for (const Vec3& p : s.points)
        for (int k = 0; k < 3; ++k) mesh->vertices.push_back(p[k]);
      mesh->indices = s.indices;
      mesh->array = std::make_unique<btTriangleIndexVertexArray>(
          int(mesh->indices.size() / 3), mesh->indices.data(), int(3 * sizeof(int)),
          int(s.points.size()), mesh->vertices.data(), int(3 * sizeof(btScalar)));
      return std::make_unique<btBvhTriangleMeshShape>(mesh->array.get(), true);
    }
  }
  return nullptr;
}

// Bullet's default 4 cm collision margin is tuned for metre-sized objects; on a hand-held 5 cm box it
// rounds the corners so much that a flat landing tumbles. Use a margin proportional to the shape.
double margin_for(const ShapeDef& s) {
  Vec3 lo, hi;
  shape_local_bounds(s, lo, hi);
  return std::min(0.004, 0.05 * (hi - lo).minCoeff());
}

std::unique_ptr<btCollisionShape> make_shape(const ShapeDef& s, std::unique_ptr<MeshStorage>& mesh) {
  auto shape = make_raw_shape(s, mesh);
  if (s.type == ShapeType::Box || s.type == ShapeType::ConvexHull) shape->setMargin(margin_for(s));
  return shape;
}

// Bit for bit (a skipped computation must be one whose result is already there, signed zeros included).
uint64_t bits_of(double x) {
  uint64_t u;
  std::memcpy(&u, &x, sizeof u);
  return u;
}
bool same_bits(const btVector3& a, const btVector3& b) {
  return bits_of(a.x()) == bits_of(b.x()) && bits_of(a.y()) == bits_of(b.y()) && bits_of(a.z()) == bits_of(b.z());
}
bool same_bits(const btTransform& a, const btTransform& b) {
  return same_bits(a.getOrigin(), b.getOrigin()) && same_bits(a.getBasis()[0], b.getBasis()[0]) &&
         same_bits(a.getBasis()[1], b.getBasis()[1]) && same_bits(a.getBasis()[2], b.getBasis()[2]);
}
}  // namespace

struct BulletBackend::Impl {
  struct Entry {
    std::unique_ptr<MeshStorage> mesh;
    std::unique_ptr<btCollisionShape> shape;
    std::unique_ptr<btRigidBody> body;
    // The last change to this kinematic body was idle's save of it unmoved (transform and interpolation
    // transform the same) over `saved_h`, in era `saved_era`, and it has been kept since (keep_kinematic): its
    // velocities are those from its transform to itself, which the same save again would write (not exactly
    // zero: the rotation's angle comes from an acos). move_kinematic, write and set_motion end it.
    bool saved_unmoved = false;
    double saved_h = 0;
    uint64_t saved_era = 0;
  };

  btDefaultCollisionConfiguration config;
  btCollisionDispatcher dispatcher{&config};
  btDbvtBroadphase broadphase;
  btSequentialImpulseConstraintSolver solver;
  btDiscreteDynamicsWorld world{&dispatcher, &broadphase, &solver, &config};
  std::vector<Entry> entries;
  std::vector<int> free_handles;
  std::vector<std::unique_ptr<btTypedConstraint>> constraints;  // null: a free constraint slot
  Entry ground;
  bool woken = true;                 // see BulletBackend::woken
  std::vector<int> moved_kinematic;  // kinematic bodies moved since the last step or idle
  std::vector<int> resaved;          // those the idle after the coming one saves again (resave_at_next_idle)
  uint64_t era = 0;  // counts Bullet's steps and restores, which change every body: a save of an older era is stale

  explicit Impl(const WorldDef& def) {
    world.setGravity(bt(def.gravity));
    // Bounds of sleeping and static bodies do not move, so Bullet need not recompute them every substep
    // (its default does, for every object: 1,000 static boxes cost ~240 us a step).
    world.setForceUpdateAllAabbs(false);
    world.getSolverInfo().m_numIterations = def.solver_iterations;
    if (def.ground) {
      // A large box rather than btStaticPlaneShape: box-box contact gives a full four-point manifold at
      // once, where the plane starts from one point and makes flat landings tumble.
      constexpr double kHalf = 1000.0;
      ground.shape = std::make_unique<btBoxShape>(btVector3(kHalf, 1.0, kHalf));
      ground.shape->setMargin(0.004);
      btRigidBody::btRigidBodyConstructionInfo info(0, nullptr, ground.shape.get());
      info.m_startWorldTransform.setOrigin(btVector3(0, def.ground_height - 1.0, 0));
      info.m_friction = def.ground_friction;
      ground.body = std::make_unique<btRigidBody>(info);
      ground.body->forceActivationState(ISLAND_SLEEPING);  // static: see apply_motion
      world.addRigidBody(ground.body.get());
    }
  }

  ~Impl() {
    for (auto& c : constraints)
      if (c) world.removeConstraint(c.get());
    for (Entry& e : entries)
      if (e.body) world.removeRigidBody(e.body.get());
    if (ground.body) world.removeRigidBody(ground.body.get());
  }

  static void apply_motion(btRigidBody& body, BodyMotion motion, double mass) {
    btVector3 inertia(0, 0, 0);
    const bool dynamic = motion == BodyMotion::Dynamic;
    if (dynamic) body.getCollisionShape()->calculateLocalInertia(mass, inertia);
    body.setMassProps(dynamic ? mass : 0, inertia);
    int flags = body.getCollisionFlags() & ~(btCollisionObject::CF_KINEMATIC_OBJECT |
                                             btCollisionObject::CF_STATIC_OBJECT);
    if (motion == BodyMotion::Kinematic) flags |= btCollisionObject::CF_KINEMATIC_OBJECT;
    if (motion == BodyMotion::Static) flags |= btCollisionObject::CF_STATIC_OBJECT;
    body.setCollisionFlags(flags);
    // Kinematic bodies are driven every frame by the hand; letting them sleep would freeze contacts. Static
    // bodies are asleep from the start: Bullet then neither updates their bounds nor collides them with
    // sleeping bodies, and still collides them with awake ones (a pair is skipped only when both sleep).
    body.forceActivationState(motion == BodyMotion::Kinematic ? DISABLE_DEACTIVATION
                              : motion == BodyMotion::Static  ? ISLAND_SLEEPING
                                                              : ACTIVE_TAG);
    body.updateInertiaTensor();
  }

  // saveKinematicState(h), skipped when it would write what the body holds already (Entry::saved_unmoved). A
  // held lid is moved at a frame's first idle substep and kept at the others (replace_children): the second
  // saves it unmoved, the rest skip.
  void save_kinematic(Entry& e, double h) const {
    if (e.saved_unmoved && e.saved_h == h && e.saved_era == era) return;
    e.saved_unmoved = same_bits(e.body->getWorldTransform(), e.body->getInterpolationWorldTransform());
    e.saved_h = h;
    e.saved_era = era;
    e.body->saveKinematicState(h);
  }

  // Wakes the dynamic bodies whose bounds touch `body`'s (Bullet's bounds carry its contact margin).
  void wake_touching(btRigidBody& body) {
    btVector3 lo, hi;
    body.getAabb(lo, hi);
    // Grown by Bullet's contact breaking threshold: a body resting on another keeps its contact that far.
    const btVector3 grow(gContactBreakingThreshold, gContactBreakingThreshold, gContactBreakingThreshold);
    lo -= grow;
    hi += grow;
    for (Entry& e : entries) {
      if (!e.body || e.body.get() == &body || e.body->isStaticOrKinematicObject()) continue;
      btVector3 elo, ehi;
      e.body->getAabb(elo, ehi);
      if (TestAabbAgainstAabb2(lo, hi, elo, ehi)) e.body->activate(true);
    }
  }

  btRigidBody& rigid(int handle) {
    return handle < 0 ? btTypedConstraint::getFixedBody() : *entries[handle].body;
  }

  int add_constraint(std::unique_ptr<btTypedConstraint> c) {
    woken = true;
    // Linked bodies do not collide with each other: the joint is what keeps them apart.
    world.addConstraint(c.get(), true);
    for (size_t i = 0; i < constraints.size(); ++i)
      if (!constraints[i]) {
        constraints[i] = std::move(c);
        return int(i);
      }
    constraints.push_back(std::move(c));
    return int(constraints.size() - 1);
  }
};

namespace {
// A frame whose Z axis is `axis` (Bullet's hinge turns about Z of its frames; the slider and the cone
// twist use X, see x_frame).
btTransform z_frame(const Vec3& origin, const Vec3& axis) {
  Quat q = Quat::FromTwoVectors(Vec3::UnitZ(), axis);
  return bt(Pose{origin, q});
}
btTransform x_frame(const Vec3& origin, const Vec3& axis) {
  Quat q = Quat::FromTwoVectors(Vec3::UnitX(), axis);
  return bt(Pose{origin, q});
}
// The child's frame that coincides with the parent's frame `in_parent` when the child sits at rest
// (relative orientation R0): child = parent * R0 at rest, so frame_child = R0^-1 * frame_parent's rotation.
btTransform child_frame(const btTransform& in_parent, const Quat& rest, const Vec3& child_point) {
  btTransform f = in_parent;
  Pose p = from_bt(in_parent);
  f.setRotation(bt(Pose{Vec3::Zero(), rest.conjugate() * p.orientation}).getRotation());
  f.setOrigin(bt(child_point));
  return f;
}
}  // namespace

int BulletBackend::add_hinge(int parent, int child, const HingeFrame& f) {
  btTransform a = z_frame(f.pivot_parent, f.axis_parent);
  btTransform b = child_frame(a, f.rest, f.pivot_child);
  auto c = std::make_unique<btHingeConstraint>(impl_->rigid(parent), impl_->rigid(child), a, b);
  if (std::isfinite(f.lower) || std::isfinite(f.upper)) {
    // Bullet measures the angle in (-pi, pi] and with the opposite sign (frame A relative to frame B); a
    // limit beyond that range cannot be expressed.
    c->setLimit(std::max(-f.upper, -M_PI), std::min(-f.lower, M_PI));
  }
  return impl_->add_constraint(std::move(c));
}

int BulletBackend::add_slider(int parent, int child, const SliderFrame& f) {
  btTransform a = x_frame(f.anchor_parent, f.axis);
  btTransform b = child_frame(a, f.rest, f.anchor_child);
  auto c = std::make_unique<btSliderConstraint>(impl_->rigid(parent), impl_->rigid(child), a, b, true);
  // Bullet reads lower > upper as "free"; keep infinite limits free that way.
  c->setLowerLinLimit(std::isfinite(f.lower) ? f.lower : 1.0);
  c->setUpperLinLimit(std::isfinite(f.upper) ? f.upper : -1.0);
  if (std::isfinite(f.lower) != std::isfinite(f.upper)) {
    c->setLowerLinLimit(std::isfinite(f.lower) ? f.lower : -1e6);
    c->setUpperLinLimit(std::isfinite(f.upper) ? f.upper : 1e6);
  }
  c->setLowerAngLimit(0);
  c->setUpperAngLimit(0);
  return impl_->add_constraint(std::move(c));
}

int BulletBackend::add_ball(int parent, int child, const BallFrame& f) {
  if (!(f.cone_half_angle < M_PI))
    return impl_->add_constraint(std::make_unique<btPoint2PointConstraint>(
        impl_->rigid(parent), impl_->rigid(child), bt(f.pivot_parent), bt(f.pivot_child)));
  btTransform a = x_frame(f.pivot_parent, f.cone_axis);
  btTransform b = child_frame(a, f.rest, f.pivot_child);
  auto c = std::make_unique<btConeTwistConstraint>(impl_->rigid(parent), impl_->rigid(child), a, b);
  c->setLimit(f.cone_half_angle, f.cone_half_angle, M_PI);  // twist about the cone axis stays free
  return impl_->add_constraint(std::move(c));
}

int BulletBackend::add_fixed(int parent, int child, const FixedFrame& f) {
  btTransform a = bt(f.relative);
  btTransform b;
  b.setIdentity();
  return impl_->add_constraint(
      std::make_unique<btFixedConstraint>(impl_->rigid(parent), impl_->rigid(child), a, b));
}

void BulletBackend::remove_constraint(int handle) {
  impl_->woken = true;
  impl_->world.removeConstraint(impl_->constraints[handle].get());
  impl_->constraints[handle].reset();
}

void BulletBackend::set_collision(int a, int b, bool enabled) {
  btRigidBody& ra = impl_->rigid(a);
  btRigidBody& rb = impl_->rigid(b);
  impl_->woken = true;
  ra.setIgnoreCollisionCheck(&rb, !enabled);
  rb.setIgnoreCollisionCheck(&ra, !enabled);
}

BulletBackend::BulletBackend(const WorldDef& def) : impl_(std::make_unique<Impl>(def)) {}
BulletBackend::~BulletBackend() = default;

int BulletBackend::add(const BodyDef& def, BodyMotion motion, int at) {
  Impl::Entry e;
  e.shape = make_shape(def.shape, e.mesh);
  btRigidBody::btRigidBodyConstructionInfo info(0, nullptr, e.shape.get());
  info.m_startWorldTransform = bt(def.pose);
  info.m_friction = def.friction;
  info.m_restitution = def.restitution;
  e.body = std::make_unique<btRigidBody>(info);
  Impl::apply_motion(*e.body, motion, def.mass);
  e.body->setLinearVelocity(bt(def.linear_velocity));
  e.body->setAngularVelocity(bt(def.angular_velocity));
  impl_->world.addRigidBody(e.body.get());
  impl_->woken = true;

  int handle;
  if (at >= 0) {
    handle = at;
    if (impl_->entries.size() <= size_t(at)) impl_->entries.resize(size_t(at) + 1);
    impl_->entries[handle] = std::move(e);
  } else if (!impl_->free_handles.empty()) {
    handle = impl_->free_handles.back();
    impl_->free_handles.pop_back();
    impl_->entries[handle] = std::move(e);
  } else {
    handle = int(impl_->entries.size());
    impl_->entries.push_back(std::move(e));
  }
  return handle;
}

void BulletBackend::remove(int handle) {
  Impl::Entry& e = impl_->entries[handle];
  impl_->world.removeRigidBody(e.body.get());
  // Bullet does not wake what rested on a removed body; wake every body whose bounds touched it.
  impl_->wake_touching(*e.body);
  impl_->woken = true;
  e = Impl::Entry();
  impl_->free_handles.push_back(handle);
}

void BulletBackend::set_motion(int handle, BodyMotion motion, double mass) {
  btRigidBody& body = *impl_->entries[handle].body;
  // Bullet caches static/kinematic state in the broadphase filter, so re-add the body after the change.
  impl_->world.removeRigidBody(&body);
  Impl::apply_motion(body, motion, mass);
  impl_->entries[handle].saved_unmoved = false;
  impl_->world.addRigidBody(&body);
  impl_->woken = true;
}

void BulletBackend::write(int handle, const Pose& pose, const Vec3& linear, const Vec3& angular) {
  btRigidBody& body = *impl_->entries[handle].body;
  impl_->entries[handle].saved_unmoved = false;
  impl_->woken = true;
  if (body.isStaticObject()) {
    // A moved static body stays asleep (see apply_motion) with its bounds brought up to date; what rested
    // on it where it was, or is hit by it where it is now, wakes.
    impl_->wake_touching(body);
    body.setWorldTransform(bt(pose));
    body.setInterpolationWorldTransform(bt(pose));
    impl_->world.updateSingleAabb(&body);
    impl_->wake_touching(body);
    return;
  }
  body.setWorldTransform(bt(pose));
  body.setInterpolationWorldTransform(bt(pose));
  body.setLinearVelocity(bt(linear));
  body.setAngularVelocity(bt(angular));
  body.setInterpolationLinearVelocity(bt(linear));
  body.setInterpolationAngularVelocity(bt(angular));
  body.activate(true);
  if (body.isKinematicObject()) impl_->moved_kinematic.push_back(handle);
}

void BulletBackend::move_kinematic(int handle, const Pose& pose) {
  Impl::Entry& e = impl_->entries[handle];
  e.body->setWorldTransform(bt(pose));
  e.saved_unmoved = false;
  impl_->moved_kinematic.push_back(handle);
}

void BulletBackend::keep_kinematic(int handle) { impl_->moved_kinematic.push_back(handle); }

void BulletBackend::resave_at_next_idle(int handle) { impl_->resaved.push_back(handle); }

void BulletBackend::read(int handle, Pose& pose, Vec3& linear, Vec3& angular) const {
  const btRigidBody& body = *impl_->entries[handle].body;
  pose = from_bt(body.getWorldTransform());
  linear = from_bt(body.getLinearVelocity());
  angular = from_bt(body.getAngularVelocity());
}

bool BulletBackend::awake(int handle) const { return impl_->entries[handle].body->isActive(); }

bool BulletBackend::woken() const { return impl_->woken; }

void BulletBackend::step(double h) {
  // maxSubSteps = 0: Bullet takes exactly one step of length h; the world does the substepping.
  impl_->world.stepSimulation(h, 0, h);
  ++impl_->era;
  impl_->woken = false;
  impl_->moved_kinematic.clear();
  impl_->resaved.clear();
}

void BulletBackend::idle(double h) {
  // What stepSimulation does first for every kinematic body (saveKinematicState): its velocity over the
  // substep and the transform the next one starts from. Unmoved kinematic bodies keep zero velocity.
  std::vector<int>& moved = impl_->moved_kinematic;
  if (moved.size() > 1) {  // (a list of one, a held lid's, is both already)
    std::sort(moved.begin(), moved.end());
    moved.erase(std::unique(moved.begin(), moved.end()), moved.end());
  }
  const std::vector<int>& resaved = impl_->resaved;
  for (int handle : moved) {
    Impl::Entry& e = impl_->entries[handle];
    if (!e.body || !e.body->isKinematicObject()) continue;
    if (std::find(resaved.begin(), resaved.end(), handle) == resaved.end()) {
      impl_->save_kinematic(e, h);
    } else {
      // What saveKinematicState leaves that the next save reads: the transform it starts from. Its velocities
      // the next save writes again. Not saved unmoved, so the next save is made.
      e.body->setInterpolationWorldTransform(e.body->getWorldTransform());
      e.saved_unmoved = false;
    }
  }
  // A kinematic body that did not move keeps its transform as the next start: nothing to save for it (its
  // velocity is recomputed by the next real step, which starts with the same save).
  moved.clear();
  impl_->resaved.clear();
}

namespace {
std::array<double, 12> numbers_of(const btTransform& t) {
  std::array<double, 12> out;
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 3; ++c) out[3 * r + c] = t.getBasis()[r][c];
  for (int k = 0; k < 3; ++k) out[9 + k] = t.getOrigin()[k];
  return out;
}
btTransform transform_of(const std::array<double, 12>& n) {
  return btTransform(btMatrix3x3(n[0], n[1], n[2], n[3], n[4], n[5], n[6], n[7], n[8]),
                     btVector3(n[9], n[10], n[11]));
}
}  // namespace

BackendState BulletBackend::state() const {
  BackendState s;
  s.bodies.resize(impl_->entries.size());
  for (size_t h = 0; h < impl_->entries.size(); ++h) {
    const btRigidBody* body = impl_->entries[h].body.get();
    if (!body) continue;
    BackendBody& b = s.bodies[h];
    b.used = true;
    b.transform = numbers_of(body->getWorldTransform());
    b.interpolation = numbers_of(body->getInterpolationWorldTransform());
    b.linear = from_bt(body->getLinearVelocity());
    b.angular = from_bt(body->getAngularVelocity());
    b.interpolation_linear = from_bt(body->getInterpolationLinearVelocity());
    b.interpolation_angular = from_bt(body->getInterpolationAngularVelocity());
    b.activation = body->getActivationState();
    b.deactivation_time = body->getDeactivationTime();
  }
  s.free_handles = impl_->free_handles;
  s.moved_kinematic = impl_->moved_kinematic;
  s.woken = impl_->woken;
  return s;
}

void BulletBackend::restore(const BackendState& s) {
  for (size_t h = 0; h < s.bodies.size() && h < impl_->entries.size(); ++h) {
    btRigidBody* body = impl_->entries[h].body.get();
    const BackendBody& b = s.bodies[h];
    if (!body || !b.used) continue;
    body->setWorldTransform(transform_of(b.transform));
    body->setInterpolationWorldTransform(transform_of(b.interpolation));
    body->setLinearVelocity(bt(b.linear));
    body->setAngularVelocity(bt(b.angular));
    body->setInterpolationLinearVelocity(bt(b.interpolation_linear));
    body->setInterpolationAngularVelocity(bt(b.interpolation_angular));
    body->forceActivationState(b.activation);
    body->setDeactivationTime(btScalar(b.deactivation_time));
    // The broadphase bounds follow the transform, as after a step.
    impl_->world.updateSingleAabb(body);
  }
  impl_->free_handles = s.free_handles;
  impl_->moved_kinematic = s.moved_kinematic;
  impl_->woken = s.woken;
  ++impl_->era;
}

}  // namespace handsim
