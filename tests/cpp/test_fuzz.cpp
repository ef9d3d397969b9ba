// A seeded random driver of the public API: valid and invalid hand frames, time steps, body and joint edits.
// Every call either succeeds or throws handsim::Error; after a rejected call the state hash is unchanged;
// after every call every state is finite and every hard joint holds. HANDSIM_FUZZ_FRAMES sets the number
// of frames, i.e. step calls (default 20,000; the sanitizer run of scripts/sanitized, part of `make test`,
// uses 100,000), HANDSIM_FUZZ_SEED the seed.
#include "handsim/def_table.h"
#include "handsim/scenes.h"

#include <gtest/gtest.h>

#include <atomic>
#include <cfloat>
#include <climits>
#include <cmath>
#include <cstdlib>
#include <limits>
#include <memory>
#include <random>
#include <thread>

using namespace handsim;

namespace {

long env_or(const char* name, long fallback) {
  const char* v = std::getenv(name);
  return v ? std::atol(v) : fallback;
}

// Counts the fields of a def table row list: 0 HANDSIM_FIELDS_X(HS_COUNT_FIELD).
#define HS_COUNT_FIELD(Def, field) +1

class Fuzzer {
 public:
  // `shared`: other threads call this world too (the ThreadsOnOneWorld test), so a rejected call's state hash
  // may differ because of them; every other check still holds between any two calls.
  explicit Fuzzer(uint64_t seed, bool shared = false) : rng_(seed), shared_(shared) {
    // 300 particles a hand (the default is 1,182): the same code paths (skinning, contacts, grasp, pose fit,
    // micro-simulator) at a quarter of the cost, so that 100,000 frames fit into `make test` under the
    // sanitizers. The run still grasps the lid (checked below).
    box_ = build_jewelry_box(world_);
    HandDef right;
    right.particle_count = 300;
    world_.add_hand(right);
    HandDef left;
    left.handedness = Handedness::Left;
    left.particle_count = 300;
    world_.add_hand(left);
  }

  // Runs until `frames` frames (step calls, accepted or rejected) have been fed; about a quarter as many
  // other calls (body, joint and id edits) are interleaved.
  void run(long frames) {
    while (steps_ < frames) {
      const int op = pick(0, 99);
      if (op < 80) step();
      else if (op < 86) edit_body();
      else if (op < 91) edit_joint();
      else if (op < 94) stale_ids();
      else extreme_def();
      check_finite();
      if (::testing::Test::HasFatalFailure()) return;
    }
  }

  long rejected() const { return rejected_; }
  long calls() const { return calls_; }
  long steps() const { return steps_; }
  long grasps() const { return grasps_; }
  World& world() { return world_; }

 private:
  int pick(int lo, int hi) { return std::uniform_int_distribution<int>(lo, hi)(rng_); }
  double uniform(double lo, double hi) { return std::uniform_real_distribution<double>(lo, hi)(rng_); }
  bool chance(double p) { return uniform(0, 1) < p; }

  // The non-finite values and the finite extremes a caller can pass in a double (issue 22 item 2): +-1e308,
  // the largest and smallest normal doubles, 1e-300, the smallest denormals, -0.0.
  double weird_number() {
    static const double values[] = {NAN,     INFINITY, -INFINITY, 0.0,     -0.0,     -1.0,    1e300,   -1e-300,
                                    1e-12,   1e308,    -1e308,    DBL_MAX, -DBL_MAX, DBL_MIN, -DBL_MIN, 1e-300,
                                    std::numeric_limits<double>::denorm_min(), -std::numeric_limits<double>::denorm_min()};
    return values[pick(0, int(std::size(values)) - 1)];
  }
  int weird_int() {
    static const int values[] = {INT_MAX, INT_MIN, INT_MAX - 1, INT_MIN + 1, 0, -1, 1, 2};
    return values[pick(0, int(std::size(values)) - 1)];
  }

  // One field of a value set to an extreme: every def field goes through these (by the def tables where the
  // def has one), so a field added to a def is fuzzed without touching this driver.
  void perturb(double& x) { x = weird_number(); }
  void perturb(int& x) { x = weird_int(); }
  void perturb(uint64_t& x) { x = chance(0.5) ? std::numeric_limits<uint64_t>::max() : 0; }
  void perturb(bool& b) { b = !b; }
  void perturb(Vec3& v) { v[pick(0, 2)] = weird_number(); }
  void perturb(Quat& q) { q.coeffs()[pick(0, 3)] = weird_number(); }
  void perturb(Pose& p) { chance(0.5) ? perturb(p.position) : perturb(p.orientation); }
  void perturb(std::optional<double>& x) { x = weird_number(); }
  void perturb(std::optional<Quat>& q) { q = Quat::Identity(); perturb(*q); }
  void perturb(BodyId& id) { id = BodyId{uint32_t(pick(0, 3)) * 0x7fffffffu, uint32_t(pick(0, 2)) * 0x7fffffffu}; }
  template <class E, std::enable_if_t<std::is_enum_v<E>, int> = 0>
  void perturb(E& e) { e = E(pick(-2, 9)); }  // out-of-range values too, as C and C# can pass them
  void perturb(ShapeDef& s) {
    switch (pick(0, 5)) {
      case 0: perturb(s.type); break;
      case 1: perturb(s.half_extents); break;
      case 2: perturb(s.radius); break;
      case 3: perturb(s.half_height); break;
      case 4:
        s.type = chance(0.5) ? ShapeType::ConvexHull : ShapeType::TriangleMesh;
        s.points = {Vec3(0, 0, 0), Vec3(0.05, 0, 0), Vec3(0, 0.05, 0), Vec3(0, 0, 0.05)};
        s.indices = {0, 1, 2, 0, 2, 3, 0, 3, 1, 1, 3, 2};
        perturb(s.points[size_t(pick(0, 3))]);
        break;
      default:
        s.type = ShapeType::TriangleMesh;
        s.points = {Vec3(0, 0, 0), Vec3(0.05, 0, 0), Vec3(0, 0.05, 0)};
        s.indices = {0, 1, 2};
        perturb(s.indices[size_t(pick(0, 2))]);
    }
  }
#define HS_PERTURB_FIELD(Def, field) \
  if (k-- == 0) perturb(d.field);
  void perturb(GraspSettings& d) {
    int k = pick(0, 0 HANDSIM_FIELDS_GRASP_SETTINGS(HS_COUNT_FIELD) - 1);
    HANDSIM_FIELDS_GRASP_SETTINGS(HS_PERTURB_FIELD)
  }
  void perturb(WorldDef& d) {
    int k = pick(0, 0 HANDSIM_FIELDS_WORLD_DEF(HS_COUNT_FIELD) - 1);
    HANDSIM_FIELDS_WORLD_DEF(HS_PERTURB_FIELD)
  }
  void perturb(BodyDef& d) {
    int k = pick(0, 0 HANDSIM_FIELDS_BODY_DEF(HS_COUNT_FIELD) - 1);
    HANDSIM_FIELDS_BODY_DEF(HS_PERTURB_FIELD)
  }
  void perturb(HandDef& d) {
    int k = pick(0, 0 HANDSIM_FIELDS_HAND_DEF(HS_COUNT_FIELD) - 1);
    HANDSIM_FIELDS_HAND_DEF(HS_PERTURB_FIELD)
  }
  void perturb(JewelryBoxDef& d) {
    int k = pick(0, 0 HANDSIM_FIELDS_JEWELRY_BOX_DEF(HS_COUNT_FIELD) - 1);
    HANDSIM_FIELDS_JEWELRY_BOX_DEF(HS_PERTURB_FIELD)
  }
#undef HS_PERTURB_FIELD
  // The joint defs have no def table (the C ABI takes them field by field): every field listed here.
  void perturb(HingeDef& d) {
    switch (pick(0, 11)) {
      case 0: perturb(d.pivot_parent); break;
      case 1: perturb(d.axis_parent); break;
      case 2: perturb(d.pivot_child); break;
      case 3: perturb(d.axis_child); break;
      case 4: perturb(d.lower); break;
      case 5: perturb(d.upper); break;
      case 6: perturb(d.damping); break;
      case 7: perturb(d.rest_orientation); break;
      case 8: perturb(d.solver); break;
      case 9: perturb(d.model); break;
      case 10: perturb(d.parent); break;
      default: perturb(d.child);
    }
  }
  void perturb(SliderDef& d) {
    switch (pick(0, 10)) {
      case 0: perturb(d.anchor_parent); break;
      case 1: perturb(d.anchor_child); break;
      case 2: perturb(d.axis); break;
      case 3: perturb(d.lower); break;
      case 4: perturb(d.upper); break;
      case 5: perturb(d.damping); break;
      case 6: perturb(d.rest_orientation); break;
      case 7: perturb(d.solver); break;
      case 8: perturb(d.model); break;
      case 9: perturb(d.parent); break;
      default: perturb(d.child);
    }
  }
  void perturb(BallDef& d) {
    switch (pick(0, 9)) {
      case 0: perturb(d.pivot_parent); break;
      case 1: perturb(d.pivot_child); break;
      case 2: perturb(d.rest_orientation); break;
      case 3: perturb(d.cone_axis); break;
      case 4: perturb(d.cone_half_angle); break;
      case 5: perturb(d.damping); break;
      case 6: perturb(d.solver); break;
      case 7: perturb(d.model); break;
      case 8: perturb(d.parent); break;
      default: perturb(d.child);
    }
  }
  void perturb(FixedDef& d) {
    switch (pick(0, 3)) {
      case 0: perturb(d.relative); break;
      case 1: perturb(d.model); break;
      case 2: perturb(d.parent); break;
      default: perturb(d.child);
    }
  }

  // Mostly a plausible hand near the box; sometimes invalid joints, far away, or garbage.
  HandFrame frame(Handedness hand) {
    const double angle = uniform(-0.5, 2.5), lift = uniform(-0.02, 0.05);
    const bool far = chance(0.05);
    const Vec3 away(uniform(-100, 100), uniform(-100, 100), uniform(-100, 100));
    HandPoseParams p = lid_pinch_shape();
    for (double& c : p.curl) c = uniform(0, 1);
    p.thumb_opposition = uniform(0, 1);
    HandFrame f;
    try {
      Pose palm = box_.lid_pinch_palm(world_, hand, angle, lift);
      if (far) palm.position += away;
      f = make_hand_frame(hand, palm, p);
    } catch (const Error&) {
      // The box may have been knocked beyond the 1e7 m a frame joint may have: the hand goes to the origin.
      f = make_hand_frame(hand, Pose{}, p);
    }
    if (chance(0.05)) f.joints[pick(0, kHandJointCount - 1)].valid = false;
    if (chance(0.03)) f.joints[kPalm].valid = false;  // tracking loss
    if (chance(0.02)) perturb(f.joints[pick(0, kHandJointCount - 1)].position);
    if (chance(0.02)) f.joints[pick(0, kHandJointCount - 1)].orientation.coeffs() *= uniform(0, 3);
    if (chance(0.01)) perturb(f.joints[pick(0, kHandJointCount - 1)].orientation);
    if (chance(0.01)) f.joints[pick(0, kHandJointCount - 1)].radius = -0.01;
    if (chance(0.01)) perturb(f.joints[pick(0, kHandJointCount - 1)].radius);
    if (chance(0.005)) f.handedness = Handedness(pick(-2, 9));
    return f;
  }

  // Runs one API call; a rejected call must leave the world exactly as it was.
  template <class F>
  void attempt(F&& call, const char* what = "") {
    last_op_ = what;
    ++calls_;
    if (std::getenv("HANDSIM_FUZZ_TRACE") && calls_ > std::atol(std::getenv("HANDSIM_FUZZ_TRACE")))
      for (BodyId b : world_.bodies())
        std::fprintf(stderr, "call %ld %s body %u y %.3g v %.3g w %.3g grasped %d\n", calls_, what, b.index,
                     world_.body_pose(b).position.y(), world_.body_linear_velocity(b).norm(),
                     world_.body_angular_velocity(b).norm(), int(world_.body_grasp(b).grasped));
    const uint64_t before = world_.state_hash();
    try {
      call();
    } catch (const Error& e) {
      ++rejected_;
      if (std::getenv("HANDSIM_FUZZ_VERBOSE")) std::fprintf(stderr, "rejected: %s\n", e.what());
      ASSERT_FALSE(e.argument().empty()) << e.what();
      if (!shared_) {
        ASSERT_EQ(world_.state_hash(), before) << e.what();
      }
    }
  }

  void step() {
    double dt = 1.0 / 60.0;
    if (chance(0.05)) dt = uniform(1e-6, 0.5);
    if (chance(0.01)) dt = weird_number();
    std::vector<HandFrame> frames;
    const int n = chance(0.01) ? 3 : pick(0, 2);
    for (int k = 0; k < n; ++k) frames.push_back(frame(k == 0 ? Handedness::Right : Handedness::Left));
    if (chance(0.01) && !frames.empty()) frames[0].handedness = Handedness::Left;
    ++steps_;
    bool accepted = false;
    if (steps_ % 2 == 0) {
      attempt([&] { world_.step(dt, frames); accepted = true; }, "step (deprecated positional)");
    } else {
      // By id, without another random draw (so the run's sequence of calls is the positional one's): the k-th
      // frame names the k-th live hand, a frame beyond them the last removed hand (stale) or the null id.
      const std::vector<HandInput> inputs = by_id(frames);
      attempt([&] { world_.step(dt, inputs); accepted = true; }, "step");
    }
    if (accepted)
      for (const Event& e : world_.events()) grasps_ += e.type == EventType::GraspBegin;
  }

  std::vector<HandInput> by_id(const std::vector<HandFrame>& frames) const {
    const std::vector<HandId> live = world_.hands();
    std::vector<HandInput> inputs;
    for (size_t k = 0; k < frames.size(); ++k) inputs.push_back({k < live.size() ? live[k] : removed_hand_, frames[k]});
    return inputs;
  }

  void edit_body() {
    const std::vector<BodyId> bodies = world_.bodies();
    const int op = pick(0, 3);
    if (op == 0 && bodies.size() < 12) {
      BodyDef d;
      d.shape = chance(0.5) ? ShapeDef::box(Vec3::Constant(uniform(0.005, 0.1))) : ShapeDef::sphere(uniform(0.005, 0.1));
      if (chance(0.05)) d.shape.radius = weird_number();
      d.mass = chance(0.1) ? weird_number() : uniform(0.01, 2);
      d.pose.position = box_.lid_front(world_) + Vec3(uniform(-0.2, 0.2), uniform(0, 0.3), uniform(-0.2, 0.2));
      attempt([&] { added_.push_back(world_.add_body(d)); }, "add_body");
    } else if (op == 1 && !added_.empty()) {
      const size_t k = size_t(pick(0, int(added_.size()) - 1));
      attempt([&] { world_.remove_body(added_[k]); }, "remove_body");
      if (!world_.contains(added_[k])) added_.erase(added_.begin() + long(k));
    } else if (op == 2 && !bodies.empty()) {
      const BodyId source = bodies[size_t(pick(0, int(bodies.size()) - 1))];
      const BodyId target = bodies[size_t(pick(0, int(bodies.size()) - 1))];
      const bool weird_y = chance(0.2), scaled = chance(0.2);
      const double y = weird_number(), scale = uniform(0, 2);
      attempt([&] {
        Pose p = world_.body_pose(source);  // inside: another thread may have removed it (shared mode)
        if (weird_y) p.position.y() = y;
        if (scaled) p.orientation.coeffs() *= scale;
        world_.set_body_pose(target, p);
      }, "set_body_pose");
    } else if (!bodies.empty()) {
      const BodyId target = bodies[size_t(pick(0, int(bodies.size()) - 1))];
      Vec3 v(uniform(-5, 5), uniform(-5, 5), uniform(-5, 5));
      if (chance(0.1)) v.x() = weird_number();
      attempt([&] { world_.set_body_velocity(target, v, Vec3::Zero()); }, "set_body_velocity");
    }
  }

  void edit_joint() {
    if (chance(0.7)) {
      const double value = chance(0.1) ? weird_number() : uniform(-1, 3);
      attempt([&] { world_.set_joint_value(box_.hinge, value); }, "set_joint_value");
      return;
    }
    if (added_.size() < 2) return;
    HingeDef h;
    h.parent = added_[0];
    h.child = added_[1];
    h.lower = uniform(-2, 1);
    h.upper = h.lower + uniform(-0.5, 7);  // sometimes lower > upper or a span over 2 pi
    h.axis_parent = chance(0.1) ? Vec3(Vec3::Zero()) : Vec3(Vec3::UnitX());
    attempt([&] { extra_joints_.push_back(world_.add_joint(h)); }, "add_joint");
    if (chance(0.5) && !extra_joints_.empty()) {
      attempt([&] { world_.remove_joint(extra_joints_.back()); }, "remove_joint");
      extra_joints_.pop_back();
    }
  }

  // A def with one field at an extreme, through the call that takes it; whatever is accepted is removed again
  // (after a step, for a hand) so that the world stays the size the rest of the driver expects.
  void extreme_def() {
    switch (pick(0, 6)) {
      case 0: {
        BodyDef d;
        d.shape = ShapeDef::box(Vec3::Constant(0.03));
        d.mass = 0.5;
        d.pose.position = box_.lid_front(world_) + Vec3(0, 0.2, 0);
        perturb(d);
        if (chance(0.3)) perturb(d);
        if (added_.size() < 12) attempt([&] { added_.push_back(world_.add_body(d)); }, "add_body (extreme)");
        break;
      }
      case 1: {
        HandDef d;
        d.particle_count = 50;  // the hand is removed after one step: the extremes, not its size, matter
        d.render_vertices = 200;
        perturb(d);
        if (d.particle_count > 2000) d.particle_count = 2000;  // a valid but large hand only costs time
        std::optional<HandId> hand;
        attempt([&] { hand = world_.add_hand(d); }, "add_hand (extreme)");
        if (!hand) break;
        step();
        attempt([&] { world_.remove_hand(*hand); removed_hand_ = *hand; }, "remove_hand");
        break;
      }
      case 2: {
        JewelryBoxDef d;
        d.position = Vec3(uniform(-3, 3), 0, uniform(2, 4));  // beside the first box
        perturb(d);
        std::optional<JewelryBox> extra;
        attempt([&] { extra = build_jewelry_box(world_, d); }, "build_jewelry_box (extreme)");
        if (!extra) break;
        check_finite();
        attempt([&] { world_.remove_joint(extra->hinge); }, "remove_joint");
        for (BodyId b : {extra->lid, extra->base, extra->table})
          if (!b.is_null()) attempt([&] { world_.remove_body(b); }, "remove_body");
        break;
      }
      case 3:
        if (added_.size() >= 2) {
          const BodyId parent = added_[size_t(pick(0, int(added_.size()) - 1))];
          const BodyId child = added_[size_t(pick(0, int(added_.size()) - 1))];
          const int kind = pick(0, 3);
          auto add = [&](auto def) {
            def.parent = parent;
            def.child = child;
            perturb(def);
            attempt([&] { extra_joints_.push_back(world_.add_joint(def)); }, "add_joint (extreme)");
          };
          if (kind == 0) add(HingeDef{});
          else if (kind == 1) add(SliderDef{});
          else if (kind == 2) add(BallDef{});
          else add(FixedDef{});
        }
        break;
      case 4: {  // a new world from an extreme WorldDef: refused, or it steps a falling box finitely
        WorldDef d;
        perturb(d);
        std::optional<World> other;
        attempt_new_world([&] { other.emplace(d); });
        if (!other) break;
        BodyDef b;
        b.mass = 1;
        b.pose.position = Vec3(0, 0.5, 0);
        const BodyId id = other->add_body(b);
        for (int k = 0; k < 3; ++k) other->step(1.0 / 60.0);
        ASSERT_TRUE(other->body_pose(id).position.allFinite() && other->body_linear_velocity(id).allFinite());
        break;
      }
      case 5: {  // the scene helper's call with extreme angle and lift
        double angle = uniform(-1, 2), lift = 0;
        chance(0.5) ? perturb(angle) : perturb(lift);
        Pose palm;
        attempt([&] { palm = box_.lid_pinch_palm(world_, Handedness::Right, angle, lift); }, "lid_pinch_palm");
        break;
      }
      default: {  // every call taking a number, with an extreme
        const std::vector<BodyId> bodies = world_.bodies();
        const BodyId target = bodies[size_t(pick(0, int(bodies.size()) - 1))];
        Vec3 v = Vec3::Zero(), w = Vec3::Zero();
        Pose change;
        change.position = Vec3::Zero();
        switch (pick(0, 3)) {
          case 0: perturb(v); attempt([&] { world_.set_body_velocity(target, v, w); }, "set_body_velocity"); break;
          case 1: perturb(w); attempt([&] { world_.set_body_velocity(target, v, w); }, "set_body_velocity"); break;
          case 2: {
            const bool moved = chance(0.5);
            moved ? perturb(change.position) : perturb(change.orientation);
            attempt([&] {
              Pose p = world_.body_pose(target);
              if (moved) p.position += change.position;
              else p.orientation = change.orientation;
              world_.set_body_pose(target, p);
            }, "set_body_pose");
            break;
          }
          default: {
            double value = 0;
            perturb(value);
            attempt([&] { world_.set_joint_value(box_.hinge, value); }, "set_joint_value");
          }
        }
      }
    }
  }

  // A World constructor either throws naming its argument or gives a world; nothing to compare a hash with.
  template <class F>
  void attempt_new_world(F&& make) {
    ++calls_;
    try {
      make();
    } catch (const Error& e) {
      ++rejected_;
      ASSERT_FALSE(e.argument().empty()) << e.what();
    }
  }

  void stale_ids() {
    if (chance(0.2)) {  // the largest ids a caller can make up
      const BodyId huge{std::numeric_limits<uint32_t>::max(), std::numeric_limits<uint32_t>::max()};
      attempt([&] { world_.set_body_velocity(huge, Vec3::Zero(), Vec3::Zero()); });
      attempt([&] { world_.remove_body(huge); });
      attempt([&] { world_.remove_hand(HandId{std::numeric_limits<uint32_t>::max(), 1}); });
    }
    BodyId foreign{uint32_t(pick(0, 40)), uint32_t(pick(0, 5))};
    attempt([&] { world_.set_body_velocity(foreign, Vec3::Zero(), Vec3::Zero()); });
    JointId stale{uint32_t(pick(0, 5)), uint32_t(pick(0, 5))};
    attempt([&] { world_.set_joint_value(stale, 0.1); });
  }

  void check_finite() {
    for (BodyId b : world_.bodies()) {
      if (shared_ && !world_.contains(b)) continue;  // an intruder's body, removed meanwhile
      Pose p;
      Vec3 v, w;
      try {
        p = world_.body_pose(b);
        v = world_.body_linear_velocity(b);
        w = world_.body_angular_velocity(b);
      } catch (const Error& e) {
        if (shared_ && e.status() == Status::StaleId) continue;  // removed between the two calls
        throw;
      }
      ASSERT_TRUE(p.position.allFinite() && p.orientation.coeffs().allFinite())
          << "body " << b.index << " after " << last_op_ << " at call " << calls_;
      ASSERT_TRUE(v.allFinite() && w.allFinite()) << "body " << b.index << " after " << last_op_;
    }
    for (JointId j : world_.joints()) {
      const JointState s = world_.joint_state(j);
      ASSERT_TRUE(std::isfinite(s.value) && std::isfinite(s.rate));
      if (s.model == JointModel::Hard) {
        const double scale = std::max(1.0, world_.body_pose(s.child).position.norm());
        ASSERT_LE(s.violation, 1e-9 * scale);
      }
    }
    for (HandId h : world_.hands()) {
      const Pose palm = world_.hand_palm_pose(h);
      ASSERT_TRUE(palm.position.allFinite() && palm.orientation.coeffs().allFinite());
    }
    const JointState lid = world_.joint_state(box_.hinge);
    ASSERT_GE(lid.value, box_.def.lower);
    ASSERT_LE(lid.value, box_.def.upper);
  }

  std::mt19937_64 rng_;
  bool shared_;
  World world_;
  JewelryBox box_;
  std::vector<BodyId> added_;
  std::vector<JointId> extra_joints_;
  long rejected_ = 0;
  long calls_ = 0;
  long steps_ = 0;
  HandId removed_hand_;  // the last hand removed: a stale id for step's by-id form
  long grasps_ = 0;
  const char* last_op_ = "";
};

}  // namespace

TEST(fuzz, RandomApiDriverKeepsTheWorldFiniteAndIntact) {
  const long frames = env_or("HANDSIM_FUZZ_FRAMES", 20000);
  Fuzzer f(uint64_t(env_or("HANDSIM_FUZZ_SEED", 1)));
  f.run(frames);
  EXPECT_EQ(f.steps(), frames);
  EXPECT_GT(f.rejected(), frames / 100);  // the driver really exercised the error paths
  if (frames >= 1000) {
    EXPECT_GT(f.grasps(), 0);  // ... and the grasp path
  }
  std::printf("fuzz: %ld frames (step calls), %ld API calls in all, %ld rejected, %ld grasps began\n", f.steps(),
              f.calls(), f.rejected(), f.grasps());
}

// Issue 22 item 2, threads: several worlds fuzzed at once, one driver per thread, each with every check of the
// driver above; and one world driven by a fuzzer while other threads call it with extreme values and read it.
// HANDSIM_FUZZ_THREAD_FRAMES frames per thread (default 2,000). Run under ASan + UBSan in scripts/sanitized
// (the races themselves are ThreadSanitizer's job: Threads.* in build/tsan).
TEST(fuzz, SeveralWorldsFuzzedInParallelThreads) {
  const long frames = env_or("HANDSIM_FUZZ_THREAD_FRAMES", 2000);
  const uint64_t seed = uint64_t(env_or("HANDSIM_FUZZ_SEED", 1));
  std::vector<std::unique_ptr<Fuzzer>> fuzzers;
  for (uint64_t k = 0; k < 3; ++k) fuzzers.push_back(std::make_unique<Fuzzer>(seed * 1000 + 11 + k));
  std::vector<std::thread> threads;
  for (auto& f : fuzzers) threads.emplace_back([&f, frames] { f->run(frames); });
  for (std::thread& t : threads) t.join();
  for (auto& f : fuzzers) {
    EXPECT_EQ(f->steps(), frames);
    EXPECT_GT(f->rejected(), frames / 100);
  }
}

TEST(fuzz, OneWorldCalledFromSeveralThreads) {
  const long frames = env_or("HANDSIM_FUZZ_THREAD_FRAMES", 2000);
  const uint64_t seed = uint64_t(env_or("HANDSIM_FUZZ_SEED", 1));
  Fuzzer driver(seed * 1000 + 7, /*shared=*/true);
  World& world = driver.world();
  std::atomic<bool> done{false};
  std::atomic<long> intruder_calls{0}, intruder_rejected{0};
  // Intruders: extreme steps, edits of any body (also the driver's), bodies of their own added and removed,
  // and reads of everything; every read must be finite whatever the other threads do.
  auto intrude = [&](uint64_t s) {
    std::mt19937_64 rng(s);
    auto pick = [&](int lo, int hi) { return std::uniform_int_distribution<int>(lo, hi)(rng); };
    const double extremes[] = {1e308, -1e308, DBL_MAX, 1e-300, std::numeric_limits<double>::denorm_min(), -0.0,
                               NAN, INFINITY, 1.0 / 60.0, 0.5, 1e-6};
    auto extreme = [&] { return extremes[pick(0, int(std::size(extremes)) - 1)]; };
    std::vector<BodyId> own;
    while (!done) {
      ++intruder_calls;
      try {
        const std::vector<BodyId> bodies = world.bodies();
        const BodyId any = bodies[size_t(pick(0, int(bodies.size()) - 1))];
        switch (pick(0, 6)) {
          case 0: world.step(extreme()); break;
          case 1: world.set_body_velocity(any, Vec3(extreme(), 0, 0), Vec3::Zero()); break;
          case 2: {
            Pose p = world.body_pose(any);
            p.position[pick(0, 2)] += pick(0, 1) ? extreme() : 0.01;
            world.set_body_pose(any, p);
            break;
          }
          case 3:
            if (own.size() < 4) {
              BodyDef d;
              d.shape = ShapeDef::sphere(pick(0, 1) ? extreme() : 0.02);
              d.mass = 0.1;
              d.pose.position = Vec3(0.3 * pick(-2, 2), 1.0, 0.3 * pick(-2, 2));
              own.push_back(world.add_body(d));
            } else {
              world.remove_body(own.back());
              own.pop_back();
            }
            break;
          default:
            for (BodyId b : bodies) {
              if (!world.contains(b)) continue;  // removed meanwhile by its owner
              const Pose p = world.body_pose(b);
              ASSERT_TRUE(p.position.allFinite() && p.orientation.coeffs().allFinite());
              ASSERT_TRUE(world.body_linear_velocity(b).allFinite());
            }
            for (JointId j : world.joints())
              if (world.contains(j)) {
                ASSERT_TRUE(std::isfinite(world.joint_state(j).value));
              }
            ASSERT_FALSE(world.events().size() > 100000);
        }
      } catch (const Error& e) {
        ++intruder_rejected;
        ASSERT_FALSE(e.argument().empty()) << e.what();
      }
    }
  };
  std::vector<std::thread> threads;
  for (uint64_t k = 0; k < 2; ++k) threads.emplace_back(intrude, seed * 1000 + 100 + k);
  driver.run(frames);
  done = true;
  for (std::thread& t : threads) t.join();
  EXPECT_EQ(driver.steps(), frames);
  EXPECT_GT(intruder_calls.load(), 0);
  EXPECT_GT(intruder_rejected.load(), 0);
  std::printf("fuzz: one world, %ld driver frames, %ld intruder calls (%ld rejected)\n", driver.steps(),
              intruder_calls.load(), intruder_rejected.load());
}
