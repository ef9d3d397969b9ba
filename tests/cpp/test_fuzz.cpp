// A seeded random driver of the public API: valid and invalid hand frames, time steps, body and joint edits.
// Every call either succeeds or throws handsim::Error; after a rejected call the state hash is unchanged;
// after every call every state is finite and every hard joint holds. HANDSIM_FUZZ_FRAMES sets the number
// of frames, i.e. step calls (default 20,000; the sanitizer run of scripts/sanitized, part of `make test`,
// uses 100,000), HANDSIM_FUZZ_SEED the seed.
#include "handsim/scenes.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdlib>
#include <random>

using namespace handsim;

namespace {

long env_or(const char* name, long fallback) {
  const char* v = std::getenv(name);
  return v ? std::atol(v) : fallback;
}

class Fuzzer {
 public:
  explicit Fuzzer(uint64_t seed) : rng_(seed) {
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
      else if (op < 92) edit_joint();
      else stale_ids();
      check_finite();
      if (::testing::Test::HasFatalFailure()) return;
    }
  }

  long rejected() const { return rejected_; }
  long calls() const { return calls_; }
  long steps() const { return steps_; }
  long grasps() const { return grasps_; }

 private:
  int pick(int lo, int hi) { return std::uniform_int_distribution<int>(lo, hi)(rng_); }
  double uniform(double lo, double hi) { return std::uniform_real_distribution<double>(lo, hi)(rng_); }
  bool chance(double p) { return uniform(0, 1) < p; }

  double weird_number() {
    static const double values[] = {NAN, INFINITY, -INFINITY, 0.0, -1.0, 1e300, -1e-300, 1e-12};
    return values[pick(0, 7)];
  }

  // Mostly a plausible hand near the box; sometimes invalid joints, far away, or garbage.
  HandFrame frame(Handedness hand) {
    const double angle = uniform(-0.5, 2.5);
    Pose palm = box_.lid_pinch_palm(world_, hand, angle, uniform(-0.02, 0.05));
    if (chance(0.05)) palm.position += Vec3(uniform(-100, 100), uniform(-100, 100), uniform(-100, 100));
    HandPoseParams p = lid_pinch_shape();
    for (double& c : p.curl) c = uniform(0, 1);
    p.thumb_opposition = uniform(0, 1);
    HandFrame f = make_hand_frame(hand, palm, p);
    if (chance(0.05)) f.joints[pick(0, kHandJointCount - 1)].valid = false;
    if (chance(0.03)) f.joints[kPalm].valid = false;  // tracking loss
    if (chance(0.02)) f.joints[pick(0, kHandJointCount - 1)].position.x() = weird_number();
    if (chance(0.02)) f.joints[pick(0, kHandJointCount - 1)].orientation.coeffs() *= uniform(0, 3);
    if (chance(0.01)) f.joints[pick(0, kHandJointCount - 1)].radius = -0.01;
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
      ASSERT_EQ(world_.state_hash(), before) << e.what();
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
    attempt([&] { world_.step(dt, frames); accepted = true; }, "step");
    if (accepted)
      for (const Event& e : world_.events()) grasps_ += e.type == EventType::GraspBegin;
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
      Pose p = world_.body_pose(bodies[size_t(pick(0, int(bodies.size()) - 1))]);
      if (chance(0.2)) p.position.y() = weird_number();
      if (chance(0.2)) p.orientation.coeffs() *= uniform(0, 2);
      const BodyId target = bodies[size_t(pick(0, int(bodies.size()) - 1))];
      attempt([&] { world_.set_body_pose(target, p); }, "set_body_pose");
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

  void stale_ids() {
    BodyId foreign{uint32_t(pick(0, 40)), uint32_t(pick(0, 5))};
    attempt([&] { world_.set_body_velocity(foreign, Vec3::Zero(), Vec3::Zero()); });
    JointId stale{uint32_t(pick(0, 5)), uint32_t(pick(0, 5))};
    attempt([&] { world_.set_joint_value(stale, 0.1); });
  }

  void check_finite() {
    for (BodyId b : world_.bodies()) {
      const Pose p = world_.body_pose(b);
      ASSERT_TRUE(p.position.allFinite() && p.orientation.coeffs().allFinite())
          << "body " << b.index << " after " << last_op_ << " at call " << calls_ << " shape "
          << int(world_.body_shape(b).type) << " mass " << world_.body_mass(b) << " motion "
          << int(world_.body_motion(b)) << " r " << world_.body_shape(b).radius;
      ASSERT_TRUE(world_.body_linear_velocity(b).allFinite() && world_.body_angular_velocity(b).allFinite());
    }
    for (JointId j : world_.joints()) {
      const JointState s = world_.joint_state(j);
      ASSERT_TRUE(std::isfinite(s.value) && std::isfinite(s.rate));
      if (s.model == JointModel::Hard) {
        const double scale = std::max(1.0, world_.body_pose(s.child).position.norm());
        ASSERT_LE(s.violation, 1e-9 * scale);
      }
    }
    const JointState lid = world_.joint_state(box_.hinge);
    ASSERT_GE(lid.value, box_.def.lower);
    ASSERT_LE(lid.value, box_.def.upper);
  }

  std::mt19937_64 rng_;
  World world_;
  JewelryBox box_;
  std::vector<BodyId> added_;
  std::vector<JointId> extra_joints_;
  long rejected_ = 0;
  long calls_ = 0;
  long steps_ = 0;
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
  if (frames >= 1000) EXPECT_GT(f.grasps(), 0);  // ... and the grasp path
  std::printf("fuzz: %ld frames (step calls), %ld API calls in all, %ld rejected, %ld grasps began\n", f.steps(),
              f.calls(), f.rejected(), f.grasps());
}
