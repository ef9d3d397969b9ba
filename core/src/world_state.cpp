// The world's state: what decides its future, in one list (visit_world) that save_state writes, restore_state
// reads and state_hash hashes, so the three cannot drift apart. The format is in docs/design.md ("Save and
// restore"); what is state and what is a cache is said field by field below.
#include "handsim/def_table.h"
#include "state_hash.h"
#include "validate.h"
#include "world_impl.h"

#include <cmath>
#include <cstdio>
#include <cstring>
#include <type_traits>
#include <utility>

namespace handsim {
namespace {

constexpr char kMagic[8] = {'H', 'S', 'I', 'M', 'S', 'T', 'A', 'T'};
constexpr uint32_t kVersion = 1;
constexpr size_t kHeaderBytes = 40;  // magic, version, header size, model fingerprint, payload size, checksum
constexpr uint32_t kNullHand = 0xffffffffu;

uint64_t checksum(const uint8_t* data, size_t size) {
  uint64_t h = 0xcbf29ce484222325ull;
  for (size_t i = 0; i < size; ++i) {
    h ^= data[i];
    h *= 0x100000001b3ull;
  }
  return h;
}

[[noreturn]] void bad_state(const std::string& message) { validate::fail("state", message); }

// --- the three visitors: each leaf is `state` (decides the future: saved and hashed) or `cache` (saved, so a
// restored world reads back the same, but a function of the state or rewritten before it is read: not hashed).

class Writer {
 public:
  std::vector<uint8_t> out;

  template <class T> void state(const T& x) { put(x); }
  template <class T> void cache(const T& x) { put(x); }
  template <class E> void enumeration(const E& x, E) { put(uint32_t(x)); }
  template <class I> void index(const I& x, uint32_t) { put(uint32_t(x)); }
  void hand(const HandId& id) { put(id.is_null() ? kNullHand : id.index); }
  void mark(uint64_t) {}
  template <class T, class F> void list(const std::vector<T>& v, F f) {
    put(uint64_t(v.size()));
    for (const T& e : v) f(e);
  }
  template <class T, class F> void cache_list(const std::vector<T>& v, F f) { list(v, f); }
  template <class T, class F> void fixed_list(const std::vector<T>& v, F f) { list(v, f); }
  void points(const Eigen::Matrix3Xd& m, Eigen::Index) {
    put(uint64_t(m.cols()));
    for (Eigen::Index i = 0; i < m.size(); ++i) put(m.data()[i]);
  }
  template <class Map, class F> void pairs(const Map& m, F f) {
    put(uint64_t(m.size()));
    for (const auto& [key, pair] : m) {
      put(key.first);
      put(key.second);
      f(key, pair);
    }
  }

 private:
  void bytes(uint64_t v, int n) {
    for (int i = 0; i < n; ++i) out.push_back(uint8_t(v >> (8 * i)));  // little-endian on every machine
  }
  void put(bool v) { bytes(v, 1); }
  void put(int v) { bytes(uint32_t(v), 4); }
  void put(uint32_t v) { bytes(v, 4); }
  void put(uint64_t v) { bytes(v, 8); }
  void put(double v) {
    uint64_t bits;
    std::memcpy(&bits, &v, sizeof bits);
    bytes(bits, 8);
  }
  void put(const Vec3& v) { for (int k = 0; k < 3; ++k) put(v[k]); }
  void put(const Quat& q) { for (int k = 0; k < 4; ++k) put(q.coeffs()[k]); }
  void put(const Pose& p) { put(p.position), put(p.orientation); }
  void put(const BoneTransform& m) { for (int i = 0; i < 12; ++i) put(m.data()[i]); }
  void put(const std::array<double, 12>& a) { for (double d : a) put(d); }
  void put(const std::vector<double>& v) {
    put(uint64_t(v.size()));
    for (double d : v) put(d);
  }
};

class Hasher {
 public:
  StateHasher h;

  template <class T> void state(const T& x) { add(x); }
  template <class T> void cache(const T&) {}
  template <class E> void enumeration(const E& x, E) { h.add(uint64_t(x)); }
  template <class I> void index(const I& x, uint32_t) { h.add(uint64_t(uint32_t(x))); }
  void hand(const HandId& id) { h.add(uint64_t(id.is_null() ? kNullHand : id.index)); }
  void mark(uint64_t v) { h.add(v); }
  template <class T, class F> void list(const std::vector<T>& v, F f) {
    h.add(uint64_t(v.size()));
    for (const T& e : v) f(e);
  }
  template <class T, class F> void cache_list(const std::vector<T>&, F) {}
  template <class T, class F> void fixed_list(const std::vector<T>& v, F f) { list(v, f); }
  void points(const Eigen::Matrix3Xd&, Eigen::Index) {}
  template <class Map, class F> void pairs(const Map& m, F f) {
    h.add(uint64_t(m.size()));
    for (const auto& [key, pair] : m) {
      h.add(uint64_t(key.first) << 32 | key.second);
      f(key, pair);
    }
  }

 private:
  void add(bool v) { h.add(uint64_t(v)); }
  void add(int v) { h.add(uint64_t(uint32_t(v))); }
  void add(uint32_t v) { h.add(uint64_t(v)); }
  void add(uint64_t v) { h.add(v); }
  void add(double v) { h.add(v); }
  void add(const Vec3& v) { h.add(v); }
  void add(const Quat& q) { h.add(q); }
  void add(const Pose& p) { h.add(p); }
  void add(const BoneTransform& m) { for (int i = 0; i < 12; ++i) h.add(m.data()[i]); }
  void add(const std::array<double, 12>& a) { for (double d : a) h.add(d); }
};

// Reads what Writer wrote. With commit false nothing is assigned (a dry run that finds every error first),
// with commit true every field is; containers are read into fresh ones and swapped in. W is World::Impl.
template <class W>
class Reader {
 public:
  Reader(const W& w, const uint8_t* data, size_t size, bool commit)
      : w_(w), p_(data), end_(data + size), begin_(data), commit_(commit) {}

  template <class T> void state(T& x) { leaf(x, true); }
  template <class T> void cache(T& x) { leaf(x, false); }
  template <class E> void enumeration(E& x, E max) {
    const uint32_t v = u32();
    if (v > uint32_t(max)) bad("an unknown " + std::string(enum_name(max)) + " " + std::to_string(v));
    if (commit_) x = E(v);
  }
  template <class I> void index(I& x, uint32_t limit) {
    const uint32_t v = u32();
    if (v >= limit) bad("an index " + std::to_string(v) + " out of range (< " + std::to_string(limit) + ")");
    if (commit_) x = I(v);
  }
  void hand(HandId& id) {
    const uint32_t v = u32();
    if (v != kNullHand && (v >= w_.hands.size() || !w_.hands[v].alive)) bad("names no live hand: slot " + std::to_string(v));
    if (commit_) id = v == kNullHand ? HandId{} : w_.hand_id(v);
  }
  void mark(uint64_t) {}
  template <class T, class F> void list(std::vector<T>& v, F f) {
    std::vector<T> fresh(count());
    for (T& e : fresh) f(e);
    if (commit_) v.swap(fresh);
  }
  template <class T, class F> void cache_list(std::vector<T>& v, F f) { list(v, f); }
  template <class T, class F> void fixed_list(std::vector<T>& v, F f) {
    const size_t n = count();
    if (n != v.size()) bad("a list of " + std::to_string(n) + " where this world has " + std::to_string(v.size()));
    std::vector<T> fresh = v;
    for (T& e : fresh) f(e);
    if (commit_) v.swap(fresh);
  }
  void points(Eigen::Matrix3Xd& m, Eigen::Index cols) {
    const size_t n = count();
    if (n != size_t(cols)) bad(std::to_string(n) + " particles where this world's hand has " + std::to_string(cols));
    Eigen::Matrix3Xd fresh(3, cols);
    for (Eigen::Index i = 0; i < fresh.size(); ++i) leaf(fresh.data()[i], false);
    if (commit_) m.swap(fresh);
  }
  template <class Map, class F> void pairs(Map& m, F f) {
    const size_t n = count();
    Map fresh;
    std::pair<uint32_t, uint32_t> last{0, 0};
    for (size_t i = 0; i < n; ++i) {
      const std::pair<uint32_t, uint32_t> key{u32(), u32()};
      if (key.first >= w_.hands.size() || !w_.hands[key.first].alive || key.second >= w_.bodies.size() ||
          !w_.bodies[key.second].alive)
        bad("a contact pair of hand slot " + std::to_string(key.first) + " and body slot " +
            std::to_string(key.second) + ", not both live here");
      if (i > 0 && !(last < key)) bad("contact pairs out of order");
      last = key;
      auto& pair = fresh.emplace(key, HandBodyPair(w_.def.grasp)).first->second;
      f(key, pair);
    }
    if (commit_) m.swap(fresh);
  }

  void finish() const {
    if (p_ != end_) bad(std::to_string(end_ - p_) + " byte(s) left over after the state");
  }

 private:
  [[noreturn]] void bad(const std::string& what) const {
    bad_state("holds " + what + " at byte " + std::to_string(kHeaderBytes + size_t(p_ - begin_)) +
              " (saved from a world built otherwise, or corrupt)");
  }
  static const char* enum_name(BodyMotion) { return "body motion"; }
  static const char* enum_name(GraspState) { return "grasp state"; }
  static const char* enum_name(JointTermination) { return "joint termination"; }

  uint64_t bytes(int n) {
    if (end_ - p_ < n) bad_state("is truncated: it ends inside the state at byte " + std::to_string(kHeaderBytes + size_t(p_ - begin_)));
    uint64_t v = 0;
    for (int i = 0; i < n; ++i) v |= uint64_t(p_[i]) << (8 * i);
    p_ += n;
    return v;
  }
  uint32_t u32() { return uint32_t(bytes(4)); }
  size_t count() {
    const uint64_t n = bytes(8);
    if (n > uint64_t(end_ - p_)) bad("a list of " + std::to_string(n) + " entries, longer than the bytes left");
    return size_t(n);
  }
  double number(bool finite) {
    const uint64_t bits = bytes(8);
    double d;
    std::memcpy(&d, &bits, sizeof d);
    if (std::isnan(d) || (finite && !std::isfinite(d))) bad("a non-finite number");
    return d;
  }
  void get(bool& v, bool) {
    const uint64_t b = bytes(1);
    if (b > 1) bad("a flag that is neither 0 nor 1");
    v = b == 1;
  }
  void get(int& v, bool) { v = int(u32()); }
  void get(uint32_t& v, bool) { v = u32(); }
  void get(uint64_t& v, bool) { v = bytes(8); }
  void get(double& v, bool finite) { v = number(finite); }
  void get(Vec3& v, bool finite) { for (int k = 0; k < 3; ++k) v[k] = number(finite); }
  void get(Quat& q, bool finite) {
    for (int k = 0; k < 4; ++k) q.coeffs()[k] = number(finite);
    if (!(std::abs(q.squaredNorm() - 1) <= 1e-6)) bad("a rotation that is not a unit quaternion");
  }
  void get(Pose& p, bool finite) { get(p.position, finite), get(p.orientation, finite); }
  void get(BoneTransform& m, bool finite) { for (int i = 0; i < 12; ++i) m.data()[i] = number(finite); }
  void get(std::array<double, 12>& a, bool finite) { for (double& d : a) d = number(finite); }
  void get(std::vector<double>& v, bool finite) {
    v.resize(count());
    for (double& d : v) d = number(finite);
  }
  template <class T> void leaf(T& x, bool finite) {
    T v = x;
    get(v, finite);
    if (commit_) x = std::move(v);
  }

  const W& w_;
  const uint8_t* p_;
  const uint8_t* end_;
  const uint8_t* begin_;
  bool commit_;
};

// --- the state, once ---

template <class V, class Face> void visit_face(V& v, Face& f, uint32_t particles) {
  v.index(f.particle, particles);
  v.state(f.normal);
  v.state(f.offset);
  v.state(f.crossing);
  v.state(f.depth);
}

// One body's, joint's and hand's state (world_impl.h: BodyState, JointSlotState, HandSlotState); S is the state
// or its const, given explicitly (Const below) so that these see nothing of the slot's model. `particles` and `groups` bound the hand's indices (from its model); `articulation` is
// keeps_articulation(def), so a world without that history saves and hashes as before.
template <class W, class T> using Const = std::conditional_t<std::is_const_v<W>, const T, T>;

template <class S, class V> void visit_body(S& b, V& v, bool paths) {
  v.state(b.pose);
  v.state(b.synced_pose);
  v.state(b.linear);
  v.state(b.angular);
  v.enumeration(b.motion, BodyMotion::Kinematic);
  v.state(b.grasp.grasped);
  v.hand(b.grasp.primary);
  v.hand(b.grasp.secondary);
  v.state(b.grasp.primary_relative);
  v.state(b.secondary_relative);
  v.state(b.supported);
  v.state(b.just_released);
  v.state(b.read_asleep);
  if (paths) std::remove_const_t<std::remove_reference_t<decltype(b.path)>>::visit_state(b.path, v);
}

template <class S, class V> void visit_joint(S& j, V& v) {
  v.state(j.value);
  v.state(j.rate);
  v.state(j.rotation);
  v.state(j.spin);
  v.state(j.solved_rotation);
  v.state(j.solved);
  v.cache(j.last.value);  // the last solve's report (joint_state); the next solve does not read it
  v.cache(j.last.cost);
  v.cache(j.last.iterations);
  v.enumeration(j.last.termination, JointTermination::AtLimit);  // (its wall time is no state)
}

template <class S, class V> void visit_hand(S& h, V& v, uint32_t particles, uint32_t groups, bool articulation) {
  v.state(h.state.tracked);
  v.state(h.has_pose);
  v.state(h.palm);
  for (auto& bone : h.state.bones) v.state(bone);
  std::remove_const_t<std::remove_reference_t<decltype(h.history)>>::visit_state(h.history, v);
  std::remove_const_t<std::remove_reference_t<decltype(h.grip)>>::visit_state(h.grip, v);
  if (articulation) std::remove_const_t<std::remove_reference_t<decltype(h.articulation)>>::visit_state(h.articulation, v);
  // Particles: skinned from the bones (lazily), deformed from the contacts of the frame. Caches.
  v.points(h.state.tracked_positions, particles);
  v.points(h.state.deformed_positions, particles);
  v.cache_list(h.state.displaced, [&](auto& p) { v.index(p, particles); });
  v.cache_list(h.displaced_centres, [&](auto& c) { v.cache(c); });
  v.cache(h.state.bounds_lo);
  v.cache(h.state.bounds_hi);
  v.cache(h.particles_current);
  v.cache(h.deformed_current);
  v.cache(h.group_bounds);
  v.cache_list(h.reach_groups, [&](auto& g) { v.index(g, groups); });
  v.cache(h.reach_groups_only);
}

// W is World::Impl (restore) or const World::Impl (save, hash); B likewise BackendState. Bullet's copy of a
// body is visited by handle, for the handles live bodies use (which handles are live is the model's).
template <class W, class B, class V> void visit_world(W& w, B& backend, V& v) {
  Const<W, WorldState>& s = w;
  v.state(s.time);
  v.state(s.accumulator);  // the part of a substep carried to the next frame
  v.state(s.awake_bodies);  // whether the next frame must run Bullet (physics_needed)
  v.cache(s.idle_substeps);
  v.cache(s.nonfinite_recoveries);
  for (uint32_t i = 0; i < w.bodies.size(); ++i) {
    if (!w.bodies[i].alive) continue;
    v.mark(uint64_t(i) << 1 | 1u);
    visit_body<Const<W, BodyState>>(w.bodies[i], v, keeps_body_paths(w.def));
  }
  for (auto& j : w.joints)
    if (j.alive) visit_joint<Const<W, JointSlotState>>(j, v);
  for (auto& h : w.hands)
    if (h.alive)
      visit_hand<Const<W, HandSlotState>>(h, v, uint32_t(h.model->particle_count()), uint32_t(h.model->particle_skin.groups.size()),
                 keeps_articulation(w.def));
  v.pairs(s.pairs, [&](const auto& key, auto& pair) {
    const uint32_t particles = uint32_t(w.hands[key.first].model->particle_count());
    std::remove_const_t<std::remove_reference_t<decltype(pair.tracker)>>::visit_state(pair.tracker, v);
    v.state(pair.previous_count);  // ContactBegin / ContactEnd are edges of it
    v.list(pair.entry_faces, [&](auto& f) { visit_face(v, f, particles); });
    v.cache_list(pair.previous_faces, [&](auto& f) { visit_face(v, f, particles); });
    v.cache_list(pair.contacts, [&](auto& c) {  // cleared before the next step's contacts
      v.index(c.particle, particles);
      v.cache(c.point);
      v.cache(c.normal);
      v.cache(c.depth);
    });
    v.cache(pair.opposing_alone);
    v.state(pair.witness[0]);  // where hand_intent looks first, and the hold path's pair (docs/grasp.md)
    v.state(pair.witness[1]);
    v.list(pair.anchor, [&](auto& bone) { v.state(bone); });  // the hold path runs while the hand is still there
    v.state(pair.anchor_pose);
    if (w.def.push_model == PushModel::Wrap) v.state(pair.let_go);  // only Wrap sets it: others save as before
    if (w.def.grasp.closing_distance > 0) v.state(pair.appeared_inside);  // only the intent rule sets it
  });
  // Bullet: its copy of every body (in Bullet's numbers) and its sleep.
  for (uint32_t h = 0; h < backend.bodies.size(); ++h) {
    auto& b = backend.bodies[h];
    if (!b.used) continue;
    v.state(b.transform);
    v.state(b.interpolation);
    v.state(b.linear);
    v.state(b.angular);
    v.state(b.interpolation_linear);
    v.state(b.interpolation_angular);
    v.index(b.activation, 6);  // Bullet's ACTIVE_TAG .. DISABLE_SIMULATION
    v.state(b.deactivation_time);
  }
  v.list(backend.moved_kinematic, [&](auto& k) { v.index(k, uint32_t(backend.bodies.size())); });
  v.state(backend.woken);
}

// --- the model a state belongs to ---

struct ModelHasher {
  StateHasher h;
  template <class T> void add(const T& v) {
    if constexpr (std::is_enum_v<T> || std::is_integral_v<T>) h.add(uint64_t(v));
    else h.add(v);
  }
  void add(const GraspSettings& g) {
#define HANDSIM_GRASP_FIELD(Def, field) add(g.field);
    HANDSIM_FIELDS_GRASP_SETTINGS(HANDSIM_GRASP_FIELD)
#undef HANDSIM_GRASP_FIELD
  }
  void add(const ShapeDef& s) {
    add(s.type), add(s.half_extents), add(s.radius), add(s.half_height);
    add(s.points.size());
    for (const Vec3& p : s.points) add(p);
    add(s.indices.size());
    for (int i : s.indices) add(i);
  }
  template <class T> void add(const std::vector<T>& v) {
    add(v.size());
    for (const T& e : v) add(e);
  }
  void add(const BodyModel& b) {
    add(b.shape), add(b.mass), add(b.friction), add(b.restitution), add(b.declared);
    add(b.backend), add(b.hard_joint), add(b.soft_joint);
  }
  void add(const JointSlotModel& j) {
    add(j.type), add(j.model), add(j.solver), add(j.parent), add(j.child), add(j.damping), add(j.length);
  }
  void add(const HandSlotModel& h) {
#define HANDSIM_HAND_FIELD(Def, field) add(h.def.field);
    HANDSIM_FIELDS_HAND_DEF(HANDSIM_HAND_FIELD)
#undef HANDSIM_HAND_FIELD
    add(h.model->particle_count()), add(h.model->particle_radius);
  }
};

// Bullet's part of the state as it now is.
template <class W> BackendState backend_state_of(const W& w) { return w.backend->state(); }

}  // namespace

uint64_t World::Impl::model_fingerprint() const {
  ModelHasher m;
#define HANDSIM_WORLD_FIELD(Def, field) m.add(def.field);
  HANDSIM_FIELDS_WORLD_DEF(HANDSIM_WORLD_FIELD)
#undef HANDSIM_WORLD_FIELD
  auto slots = [&m](const auto& table, auto as_model) {
    for (const auto& slot : table) {
      m.add(slot.alive);
      if (slot.alive) m.add(as_model(slot));
    }
  };
  slots(bodies, [](const Body& b) -> const BodyModel& { return b; });
  slots(joints, [](const Joint& j) -> const JointSlotModel& { return j; });
  slots(hands, [](const HandSlot& h) -> const HandSlotModel& { return h; });
  // Where the next add puts its body, joint or hand: part of building alike.
  m.add(free_body_slots), m.add(free_joint_slots), m.add(free_hand_slots);
  m.add(backend_state_of(*this).free_handles);
  return m.h.value();
}

// How the restored leaves fit together, which the reader cannot check leaf by leaf: a grasp has its primary
// hand, a body's motion is one its declaration allows, a hand's lists agree in length, histories are in time
// order (their velocity slopes divide by the time spread). Empty when consistent.
std::string World::Impl::inconsistency() const {
  for (uint32_t i = 0; i < bodies.size(); ++i) {
    const Body& b = bodies[i];
    if (!b.alive) continue;
    const std::string body = "body slot " + std::to_string(i);
    const GraspInfo& g = b.grasp;
    if (g.grasped == g.primary.is_null() || (!g.secondary.is_null() && (!g.grasped || g.secondary.index == g.primary.index)))
      return body + " has a grasp without its hands";
    const bool allowed = b.motion == b.declared || (b.declared == BodyMotion::Dynamic && b.motion == BodyMotion::Kinematic);
    if (!allowed) return body + " moves in a way its definition does not allow";
    // The bounds every caller's pose and velocity are held to (validate.h).
    if (!(b.pose.position.cwiseAbs().maxCoeff() <= validate::kMaxCoordinate) ||
        !(std::max(b.linear.norm(), b.angular.norm()) <= validate::kMaxSpeed))
      return body + " is beyond the bounds of a pose or speed";
    if (!b.path.in_time_order()) return body + " has a path out of time order";
  }
  for (uint32_t i = 0; i < hands.size(); ++i) {
    const HandSlot& h = hands[i];
    if (!h.alive) continue;
    const std::string hand = "hand slot " + std::to_string(i);
    const size_t groups = h.model->particle_skin.groups.size();
    if (h.state.displaced.size() != h.displaced_centres.size()) return hand + " has displaced particles without centres";
    if (!h.group_bounds.empty() && h.group_bounds.size() != 6 * groups) return hand + " has group boxes of another hand";
    if (!h.history.in_time_order() || !h.grip.in_time_order() || !h.articulation.in_time_order())
      return hand + " has a history out of time order";
  }
  for (const auto& [key, pair] : pairs) {
    const int particles = hands[key.first].model->particle_count();
    const std::string name = "the pair of hand slot " + std::to_string(key.first) + " and body slot " + std::to_string(key.second);
    for (int p : pair.witness)
      if (p < -1 || p >= particles) return name + " has a witness particle out of range";
    if (!pair.anchor.empty() && pair.anchor.size() != kHandJointCount) return name + " has an anchor of another hand";
  }
  return {};
}

uint64_t World::Impl::state_hash() const {
  const BackendState backend = backend_state_of(*this);
  Hasher v;
  visit_world(*this, backend, v);
  return v.h.value();
}

std::vector<uint8_t> World::Impl::save_state() {
  particles().complete_all_contacts();  // the saved contacts and deformation are whole, so a restored world reads them back
  const BackendState backend = backend_state_of(*this);
  Writer payload;
  visit_world(std::as_const(*this), backend, payload);
  std::vector<uint8_t> out(kMagic, kMagic + 8);
  auto put = [&out](uint64_t v, int n) {
    for (int i = 0; i < n; ++i) out.push_back(uint8_t(v >> (8 * i)));
  };
  put(kVersion, 4);
  put(kHeaderBytes, 4);
  put(model_fingerprint(), 8);
  put(payload.out.size(), 8);
  put(checksum(payload.out.data(), payload.out.size()), 8);
  out.insert(out.end(), payload.out.begin(), payload.out.end());
  // The saving world continues from the same rebuilt Bullet scene as every world restored from `out`.
  restore_state(out.data(), out.size(), true);
  return out;
}

void World::Impl::restore_state(const uint8_t* data, size_t size, bool keep_events) {
  if (!data && size > 0) bad_state("is null");
  if (size < kHeaderBytes)
    bad_state("is " + std::to_string(size) + " bytes, shorter than the " + std::to_string(kHeaderBytes) +
              "-byte header (truncated, or not from save_state)");
  if (std::memcmp(data, kMagic, 8) != 0) bad_state("does not start with HSIMSTAT: not from save_state");
  auto word = [data](size_t at, int n) {
    uint64_t v = 0;
    for (int i = 0; i < n; ++i) v |= uint64_t(data[at + i]) << (8 * i);
    return v;
  };
  const uint64_t version = word(8, 4);
  if (version != kVersion)
    bad_state("has format version " + std::to_string(version) + "; this build reads version " + std::to_string(kVersion));
  if (word(12, 4) != kHeaderBytes) bad_state("has a header of " + std::to_string(word(12, 4)) + " bytes, not " + std::to_string(kHeaderBytes));
  const uint64_t model = word(16, 8), payload = word(24, 8), sum = word(32, 8);
  if (payload != size - kHeaderBytes)
    bad_state("is truncated or padded: the header announces " + std::to_string(payload) + " bytes of state, " +
              std::to_string(size - kHeaderBytes) + " follow");
  if (checksum(data + kHeaderBytes, payload) != sum) bad_state("is corrupt: its checksum does not match");
  const uint64_t here = model_fingerprint();
  if (model != here) {
    char message[200];
    std::snprintf(message, sizeof message,
                  "was saved from a world with other settings, bodies, joints or hands (model 0x%016llx, this "
                  "world 0x%016llx)",
                  (unsigned long long)model, (unsigned long long)here);
    bad_state(message);
  }
  BackendState backend = backend_state_of(*this);  // which handles are live; the rest is read
  {
    Reader<Impl> dry(*this, data + kHeaderBytes, payload, false);  // every error is found before anything changes
    visit_world(*this, backend, dry);
    dry.finish();
  }
  // The state as it is, to put back should the leaves turn out not to fit together.
  Writer backup;
  const BackendState current = backend_state_of(*this);
  visit_world(std::as_const(*this), current, backup);
  Reader<Impl> read(*this, data + kHeaderBytes, payload, true);
  visit_world(*this, backend, read);
  if (const std::string why = inconsistency(); !why.empty()) {
    BackendState unused = current;
    Reader<Impl> undo(*this, backup.out.data(), backup.out.size(), true);
    visit_world(*this, unused, undo);  // Bullet's scene was not touched yet
    bad_state("does not fit together: " + why + " (saved from a world built otherwise, or corrupt)");
  }
  // What follows from the state.
  held.clear();
  released.clear();
  pathed.clear();
  for (uint32_t i = 0; i < bodies.size(); ++i) {
    if (!bodies[i].alive) continue;
    if (bodies[i].grasp.grasped) held.push_back(i);
    if (bodies[i].just_released) released.push_back(i);
    if (bodies[i].path.size() > 0) pathed.push_back(i);
    update_box(bodies, i);
  }
  box_order_dirty = true;
  ++motion_version;
  ++body_version;  // the hands' Bullet particle colliders are rebuilt
  for (HandSlot& h : hands) {
    h.render_dirty = true;
    h.bullet_particles.reset();
    h.bullet_bodies.clear();
  }
  rebuild_backend(backend);
  if (!keep_events) {
    events.clear();
    step_events = 0;
    report = StepReport();
  }
}

// A new Bullet scene: the bodies added in handle order, then the joints' constraints and collision exceptions
// in joint order, then Bullet's saved copy of each body and its sleep. The same for every world that does it
// from the same state; the contact caches of the old scene are gone.
void World::Impl::rebuild_backend(const BackendState& saved) {
  auto fresh = std::make_unique<BulletBackend>(def);
  std::vector<uint32_t> by_handle(saved.bodies.size(), UINT32_MAX);
  for (uint32_t i = 0; i < bodies.size(); ++i)
    if (bodies[i].alive) by_handle[size_t(bodies[i].backend)] = i;
  for (size_t handle = 0; handle < by_handle.size(); ++handle) {
    if (by_handle[handle] == UINT32_MAX) continue;
    const Body& b = bodies[by_handle[handle]];
    BodyDef d;
    d.shape = b.shape;
    d.mass = b.mass;
    d.pose = b.pose;
    d.linear_velocity = b.linear;
    d.angular_velocity = b.angular;
    d.friction = b.friction;
    d.restitution = b.restitution;
    d.kinematic = b.declared == BodyMotion::Kinematic;
    fresh->add(d, b.motion, int(handle));
  }
  for (Joint& j : joints) {
    if (!j.alive) continue;
    const int parent = j.parent == kWorldParent ? -1 : bodies[j.parent].backend;
    const int child = bodies[j.child].backend;
    if (j.model == JointModel::Hard) {
      if (parent >= 0) fresh->set_collision(parent, child, false);
      continue;
    }
    switch (j.type) {
      case JointType::Hinge: j.constraint = fresh->add_hinge(parent, child, j.hinge); break;
      case JointType::Slider: j.constraint = fresh->add_slider(parent, child, j.slider); break;
      case JointType::Ball: j.constraint = fresh->add_ball(parent, child, j.ball); break;
      case JointType::Fixed: j.constraint = fresh->add_fixed(parent, child, j.fixed); break;
    }
  }
  fresh->restore(saved);
  backend = std::move(fresh);
}

uint64_t World::state_hash() const {
  const auto held = lock();
  return impl_->state_hash();
}

std::vector<uint8_t> World::save_state() {
  const auto held = lock();
  return impl_->save_state();
}

void World::restore_state(const std::vector<uint8_t>& state) { restore_state(state.data(), state.size()); }

void World::restore_state(const uint8_t* data, size_t size) {
  const auto held = lock();
  impl_->restore_state(data, size, false);
}

}  // namespace handsim
