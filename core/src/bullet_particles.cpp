#include "bullet_particles.h"

#include "validate.h"

#include <btBulletCollisionCommon.h>

#include <algorithm>

namespace handsim {
namespace {

// Particles only meet bodies: the broadphase never pairs two particles.
constexpr int kParticleGroup = 1 << 6;
constexpr int kBodyGroup = 1 << 7;

btTransform to_bt(const Pose& p) {
  Quat q = p.orientation.normalized();
  return btTransform(btQuaternion(btScalar(q.x()), btScalar(q.y()), btScalar(q.z()), btScalar(q.w())),
                     btVector3(btScalar(p.position.x()), btScalar(p.position.y()), btScalar(p.position.z())));
}

Vec3 from_bt(const btVector3& v) { return Vec3(v.x(), v.y(), v.z()); }

}  // namespace

struct BulletParticleCollider::Impl {
  btDefaultCollisionConfiguration config;
  btCollisionDispatcher dispatcher{&config};
  btDbvtBroadphase broadphase;
  btCollisionWorld world{&dispatcher, &broadphase, &config};
  btSphereShape particle_shape;
  std::vector<std::unique_ptr<btCollisionObject>> particles, bodies;
  std::vector<std::unique_ptr<btCollisionShape>> shapes;
  std::vector<std::unique_ptr<btTriangleIndexVertexArray>> mesh_arrays;
  std::vector<std::vector<btScalar>> mesh_vertices;
  std::vector<std::vector<int>> mesh_indices;

  explicit Impl(double r) : particle_shape(btScalar(r)) {}
  ~Impl() {
    for (auto& o : particles) world.removeCollisionObject(o.get());
    for (auto& o : bodies) world.removeCollisionObject(o.get());
  }
};

BulletParticleCollider::BulletParticleCollider(int particle_count, double particle_radius)
    : impl_(std::make_unique<Impl>(particle_radius)) {
  validate::positive(particle_radius, "particle_radius");
  for (int i = 0; i < particle_count; ++i) {
    auto o = std::make_unique<btCollisionObject>();
    o->setCollisionShape(&impl_->particle_shape);
    o->setUserIndex(i);
    o->setUserIndex2(-1);
    impl_->world.addCollisionObject(o.get(), kParticleGroup, kBodyGroup);
    impl_->particles.push_back(std::move(o));
  }
}

BulletParticleCollider::~BulletParticleCollider() = default;

int BulletParticleCollider::add_body(const ShapeDef& s, const Pose& pose) {
  validate_shape(s, "shape");
  std::unique_ptr<btCollisionShape> shape;
  switch (s.type) {
    case ShapeType::Box: {
      auto box = std::make_unique<btBoxShape>(btVector3(btScalar(s.half_extents.x()), btScalar(s.half_extents.y()),
                                                        btScalar(s.half_extents.z())));
      // Bullet's default margin rounds the box edges (radius up to 10% of the smallest half extent);
      // without a margin the sphere-box algorithm is the exact closed form.
      box->setMargin(0);
      shape = std::move(box);
      break;
    }
    case ShapeType::Sphere: shape = std::make_unique<btSphereShape>(btScalar(s.radius)); break;
    case ShapeType::Capsule:
      shape = std::make_unique<btCapsuleShape>(btScalar(s.radius), btScalar(2 * s.half_height));
      break;
    case ShapeType::ConvexHull: {
      auto hull = std::make_unique<btConvexHullShape>();
      for (const Vec3& p : s.points) hull->addPoint(btVector3(btScalar(p.x()), btScalar(p.y()), btScalar(p.z())), false);
      hull->recalcLocalAabb();
      hull->setMargin(0);
      shape = std::move(hull);
      break;
    }
    case ShapeType::TriangleMesh: {
      std::vector<btScalar> v;
      for (const Vec3& p : s.points) v.insert(v.end(), {btScalar(p.x()), btScalar(p.y()), btScalar(p.z())});
      impl_->mesh_vertices.push_back(std::move(v));
      impl_->mesh_indices.push_back(s.indices);
      auto arr = std::make_unique<btTriangleIndexVertexArray>(
          int(s.indices.size() / 3), impl_->mesh_indices.back().data(), 3 * int(sizeof(int)),
          int(s.points.size()), impl_->mesh_vertices.back().data(), 3 * int(sizeof(btScalar)));
      shape = std::make_unique<btBvhTriangleMeshShape>(arr.get(), true);
      impl_->mesh_arrays.push_back(std::move(arr));
      break;
    }
  }
  auto o = std::make_unique<btCollisionObject>();
  o->setCollisionShape(shape.get());
  o->setWorldTransform(to_bt(validate::pose(pose, "pose")));
  o->setUserIndex(-1);
  o->setUserIndex2(int(impl_->bodies.size()));
  impl_->world.addCollisionObject(o.get(), kBodyGroup, kParticleGroup);
  impl_->shapes.push_back(std::move(shape));
  impl_->bodies.push_back(std::move(o));
  return int(impl_->bodies.size()) - 1;
}

void BulletParticleCollider::set_body_pose(int body, const Pose& pose) {
  if (body < 0 || body >= int(impl_->bodies.size())) validate::fail("body", "out of range");
  impl_->bodies[body]->setWorldTransform(to_bt(validate::pose(pose, "pose")));
}

void BulletParticleCollider::collide(const Eigen::Matrix3Xd& centres,
                                     std::vector<std::vector<ParticleContact>>& out) {
  if (centres.cols() != Eigen::Index(impl_->particles.size()))
    validate::fail("centres", "must have one column per particle");
  for (Eigen::Index i = 0; i < centres.cols(); ++i) {
    btTransform t;
    t.setIdentity();
    t.setOrigin(btVector3(btScalar(centres(0, i)), btScalar(centres(1, i)), btScalar(centres(2, i))));
    impl_->particles[i]->setWorldTransform(t);
  }
  impl_->world.performDiscreteCollisionDetection();

  out.assign(impl_->bodies.size(), {});
  btDispatcher* d = impl_->world.getDispatcher();
  for (int m = 0; m < d->getNumManifolds(); ++m) {
    const btPersistentManifold* man = d->getManifoldByIndexInternal(m);
    const btCollisionObject* a = man->getBody0();
    const btCollisionObject* b = man->getBody1();
    const bool particle_is_a = a->getUserIndex() >= 0;
    const int particle = particle_is_a ? a->getUserIndex() : b->getUserIndex();
    const int body = particle_is_a ? b->getUserIndex2() : a->getUserIndex2();
    if (particle < 0 || body < 0) continue;
    int deepest = -1;
    for (int c = 0; c < man->getNumContacts(); ++c)
      if (deepest < 0 || man->getContactPoint(c).getDistance() < man->getContactPoint(deepest).getDistance())
        deepest = c;
    if (deepest < 0) continue;
    const btManifoldPoint& pt = man->getContactPoint(deepest);
    double depth = -double(pt.getDistance());
    if (depth <= 0) continue;
    // normalWorldOnB points from B towards A.
    ParticleContact c;
    c.particle = particle;
    c.depth = depth;
    c.normal = particle_is_a ? from_bt(pt.m_normalWorldOnB) : Vec3(-from_bt(pt.m_normalWorldOnB));
    c.point = particle_is_a ? from_bt(pt.getPositionWorldOnB()) : from_bt(pt.getPositionWorldOnA());
    out[body].push_back(c);
  }
  for (auto& v : out)
    std::sort(v.begin(), v.end(), [](const ParticleContact& x, const ParticleContact& y) { return x.particle < y.particle; });
}

}  // namespace handsim
