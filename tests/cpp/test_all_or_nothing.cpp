// Issue 22 item 5: every composite call is all-or-nothing. Each call that changes several things (the scene
// builder, add_body, add_hand, add_joint of every type, set_body_pose / set_body_velocity / set_joint_value,
// which move joint children too, remove_*, step) is fed, field by field, every extreme a caller can pass
// (NaN, +-inf, +-1e308, +-DBL_MAX, 1e-300, the smallest denormal, -0.0, -1, and the int extremes) in a busy
// world (a jewelry box, two hands grasping the lid, free bodies, a soft and a hard joint). A rejected call names
// its argument and leaves the state hash and the body, joint, hand and event counts as they were; an accepted
// one leaves every state finite (it is then undone, so that the next value meets the same world). The def
// fields are walked through the def tables (def_table.h), so a new field is covered without a new row here.
#include "handsim/def_table.h"
#include "handsim/scenes.h"

#include <gtest/gtest.h>

#include <cfloat>
#include <climits>
#include <cmath>
#include <functional>
#include <limits>
#include <optional>
#include <string>
#include <vector>

using namespace handsim;

namespace {

constexpr double kDt = 1.0 / 60.0;

std::vector<double> extremes(double) {
  const double denormal = std::numeric_limits<double>::denorm_min();
  return {NAN, INFINITY, -INFINITY, 1e308, -1e308, DBL_MAX, -DBL_MAX, 1e-300, denormal, -denormal, -0.0, -1.0};
}
std::vector<int> extremes(int) { return {INT_MAX, INT_MIN, -1, 0}; }
std::vector<uint64_t> extremes(uint64_t) { return {0, std::numeric_limits<uint64_t>::max()}; }
std::vector<bool> extremes(bool b) { return {!b}; }
template <class E, std::enable_if_t<std::is_enum_v<E>, int> = 0>
std::vector<E> extremes(E) {
  return {E(-1), E(99)};  // out of range, as C and C# can pass them
}
std::vector<Vec3> extremes(const Vec3& v) {
  std::vector<Vec3> out;
  for (double x : extremes(0.0))
    for (int k = 0; k < 3; ++k) {
      Vec3 e = v;
      e[k] = x;
      out.push_back(e);
    }
  return out;
}
std::vector<Quat> extremes(const Quat& q) {
  std::vector<Quat> out;
  for (double x : extremes(0.0))
    for (int k = 0; k < 4; ++k) {
      Quat e = q;
      e.coeffs()[k] = x;
      out.push_back(e);
    }
  return out;
}
std::vector<Pose> extremes(const Pose& p) {
  std::vector<Pose> out;
  for (const Vec3& v : extremes(p.position)) out.push_back({v, p.orientation});
  for (const Quat& q : extremes(p.orientation)) out.push_back({p.position, q});
  return out;
}
std::vector<BodyId> extremes(BodyId) {
  return {BodyId{0xffffffffu, 0xffffffffu}, BodyId{0, 0xffffffffu}, BodyId{1, 12345}};
}
std::vector<std::optional<double>> extremes(const std::optional<double>&) {
  std::vector<std::optional<double>> out;
  for (double x : extremes(0.0)) out.push_back(x);
  return out;
}
std::vector<std::optional<Quat>> extremes(const std::optional<Quat>&) {
  std::vector<std::optional<Quat>> out;
  for (const Quat& q : extremes(Quat::Identity())) out.push_back(q);
  return out;
}
std::vector<ShapeDef> extremes(const ShapeDef& s) {
  std::vector<ShapeDef> out;
  for (ShapeType t : extremes(s.type)) out.push_back(s), out.back().type = t;
  for (const Vec3& v : extremes(s.half_extents)) out.push_back(s), out.back().half_extents = v;
  for (double r : extremes(0.0)) {
    out.push_back(ShapeDef::sphere(r));
    out.push_back(ShapeDef::capsule(r, 0.02));
    out.push_back(ShapeDef::capsule(0.02, r));
  }
  const std::vector<Vec3> tetra = {Vec3(0, 0, 0), Vec3(0.05, 0, 0), Vec3(0, 0.05, 0), Vec3(0, 0, 0.05)};
  for (const Vec3& p : extremes(Vec3(0.05, 0.05, 0.05))) {
    std::vector<Vec3> points = tetra;
    points[3] = p;
    out.push_back(ShapeDef::convex_hull(points));
    out.push_back(ShapeDef::triangle_mesh(points, {0, 1, 2, 0, 2, 3}));
  }
  for (int index : extremes(0)) out.push_back(ShapeDef::triangle_mesh(tetra, {0, 1, index}));
  out.push_back(ShapeDef::triangle_mesh(tetra, {0, 1}));  // not a whole triangle
  out.push_back(ShapeDef::convex_hull({}));
  return out;
}

// Every copy of `def` with one field at one of its extremes, via the def table's rows.
#define HS_FIELD_VARIANTS(Def, field)                               \
  for (const auto& value : extremes(def.field)) {                   \
    Def copy = def;                                                 \
    copy.field = value;                                             \
    out.push_back({copy, #field});                                  \
  }
template <class Def>
struct Variant {
  Def def;
  const char* field;
};
std::vector<Variant<BodyDef>> variants(const BodyDef& def) {
  std::vector<Variant<BodyDef>> out;
  HANDSIM_FIELDS_BODY_DEF(HS_FIELD_VARIANTS)
  return out;
}
std::vector<Variant<HandDef>> variants(const HandDef& def) {
  std::vector<Variant<HandDef>> out;
  HANDSIM_FIELDS_HAND_DEF(HS_FIELD_VARIANTS)
  return out;
}
std::vector<Variant<JewelryBoxDef>> variants(const JewelryBoxDef& def) {
  std::vector<Variant<JewelryBoxDef>> out;
  HANDSIM_FIELDS_JEWELRY_BOX_DEF(HS_FIELD_VARIANTS)
  return out;
}
// The joint defs have no def table (the C ABI takes them field by field): their fields listed here.
#define HS_HINGE_FIELDS(X) \
  X(HingeDef, parent) X(HingeDef, child) X(HingeDef, pivot_parent) X(HingeDef, axis_parent) X(HingeDef, pivot_child) \
  X(HingeDef, axis_child) X(HingeDef, lower) X(HingeDef, upper) X(HingeDef, damping) X(HingeDef, rest_orientation)   \
  X(HingeDef, solver) X(HingeDef, model)
#define HS_SLIDER_FIELDS(X)                                                                                    \
  X(SliderDef, parent) X(SliderDef, child) X(SliderDef, anchor_parent) X(SliderDef, anchor_child)              \
  X(SliderDef, axis) X(SliderDef, lower) X(SliderDef, upper) X(SliderDef, damping) X(SliderDef, rest_orientation) \
  X(SliderDef, solver) X(SliderDef, model)
#define HS_BALL_FIELDS(X)                                                                                  \
  X(BallDef, parent) X(BallDef, child) X(BallDef, pivot_parent) X(BallDef, pivot_child)                    \
  X(BallDef, rest_orientation) X(BallDef, cone_axis) X(BallDef, cone_half_angle) X(BallDef, damping)      \
  X(BallDef, solver) X(BallDef, model)
#define HS_FIXED_FIELDS(X) X(FixedDef, parent) X(FixedDef, child) X(FixedDef, relative) X(FixedDef, model)
std::vector<Variant<HingeDef>> variants(const HingeDef& def) {
  std::vector<Variant<HingeDef>> out;
  HS_HINGE_FIELDS(HS_FIELD_VARIANTS)
  return out;
}
std::vector<Variant<SliderDef>> variants(const SliderDef& def) {
  std::vector<Variant<SliderDef>> out;
  HS_SLIDER_FIELDS(HS_FIELD_VARIANTS)
  return out;
}
std::vector<Variant<BallDef>> variants(const BallDef& def) {
  std::vector<Variant<BallDef>> out;
  HS_BALL_FIELDS(HS_FIELD_VARIANTS)
  return out;
}
std::vector<Variant<FixedDef>> variants(const FixedDef& def) {
  std::vector<Variant<FixedDef>> out;
  HS_FIXED_FIELDS(HS_FIELD_VARIANTS)
  return out;
}
#undef HS_FIELD_VARIANTS

struct Snapshot {
  uint64_t hash;
  size_t bodies, joints, hands, events;
  bool operator==(const Snapshot& o) const {
    return hash == o.hash && bodies == o.bodies && joints == o.joints && hands == o.hands && events == o.events;
  }
};
Snapshot snapshot(const World& w) {
  return {w.state_hash(), w.bodies().size(), w.joints().size(), w.hands().size(), w.events().size()};
}

void expect_finite(const World& w, const std::string& what) {
  for (BodyId b : w.bodies()) {
    const Pose p = w.body_pose(b);
    ASSERT_TRUE(p.position.allFinite() && p.orientation.coeffs().allFinite() && w.body_linear_velocity(b).allFinite() &&
                w.body_angular_velocity(b).allFinite())
        << what;
  }
  for (JointId j : w.joints()) {
    const JointState s = w.joint_state(j);
    ASSERT_TRUE(std::isfinite(s.value) && std::isfinite(s.rate)) << what;
  }
}

// A busy world: the jewelry box with both hands on the lid (grasped), two free cubes, a soft ball joint
// between them and a hard hinge from the world to a third cube.
struct Busy {
  World world;
  JewelryBox box;
  BodyId a, b, c;
  JointId soft, hard;
  HandId right_hand, left_hand;
  int frame = 0;

  Busy() {
    box = build_jewelry_box(world);
    HandDef right;
    right.particle_count = 150;
    right_hand = world.add_hand(right);
    HandDef left = right;
    left.handedness = Handedness::Left;
    left_hand = world.add_hand(left);
    a = world.add_body(cube(Vec3(0.6, 0.3, 0.2)));
    b = world.add_body(cube(Vec3(0.6, 0.5, 0.2)));
    c = world.add_body(cube(Vec3(-0.6, 0.5, 0.2)));
    BallDef ball;
    ball.parent = a;
    ball.child = b;
    ball.pivot_parent = Vec3(0, 0.1, 0);
    ball.pivot_child = Vec3(0, -0.1, 0);
    ball.model = JointModel::Soft;
    soft = world.add_joint(ball);
    HingeDef hinge;
    hinge.child = c;
    hinge.pivot_parent = Vec3(-0.6, 0.6, 0.2);
    hinge.pivot_child = Vec3(0, 0.1, 0);
    hard = world.add_joint(hinge);
    for (int i = 0; i < 150; ++i) advance();
  }
  static BodyDef cube(const Vec3& at) {
    BodyDef d;
    d.shape = ShapeDef::box(Vec3::Constant(0.03));
    d.mass = 0.3;
    d.pose.position = at;
    return d;
  }
  // scenario_frames' right and left frame, to their hands.
  std::vector<HandInput> inputs(const std::vector<HandFrame>& f) const { return {{right_hand, f[0]}, {left_hand, f[1]}}; }
  void advance() { world.step(kDt, inputs(scenario_frames(box, world, frame++))); }

  // Runs `call`; rejected: named and nothing changed; accepted: finite, then `undo`.
  // Returns whether it was rejected.
  bool attempt(const std::string& what, const std::function<void()>& call, const std::function<void()>& undo = {}) {
    const Snapshot before = snapshot(world);
    try {
      call();
    } catch (const Error& e) {
      EXPECT_FALSE(e.argument().empty()) << what << ": " << e.what();
      EXPECT_TRUE(snapshot(world) == before) << what << " was rejected (" << e.what() << ") but changed the world";
      return true;
    }
    expect_finite(world, what + " (accepted)");
    if (undo) undo();
    return false;
  }
};

template <class Def, class Call>
int walk(Busy& busy, const char* call_name, const Def& good, Call call) {
  int rejected = 0;
  for (const auto& v : variants(good)) rejected += busy.attempt(std::string(call_name) + " " + v.field, [&] { call(v.def); });
  return rejected;
}

}  // namespace

TEST(AllOrNothing, SceneBuilderAndAddBodyAndAddHand) {
  Busy busy;
  World& w = busy.world;
  BodyDef body = Busy::cube(Vec3(0, 1.5, 0.5));
  const int bodies_rejected = walk(busy, "add_body", body, [&](const BodyDef& d) {
    const BodyId id = w.add_body(d);
    w.remove_body(id);
  });
  EXPECT_GT(bodies_rejected, 50);
  HandDef hand;
  hand.particle_count = 60;
  hand.render_vertices = 500;
  const int hands_rejected = walk(busy, "add_hand", hand, [&](const HandDef& d) {
    const HandId id = w.add_hand(d);
    w.step(kDt);
    w.remove_hand(id);
  });
  EXPECT_GT(hands_rejected, 10);
  JewelryBoxDef box;
  box.position = Vec3(0, 0, 3);
  const int boxes_rejected = walk(busy, "build_jewelry_box", box, [&](const JewelryBoxDef& d) {
    const JewelryBox made = build_jewelry_box(w, d);
    w.step(kDt);
    w.remove_joint(made.hinge);
    for (BodyId b : {made.lid, made.base, made.table})
      if (!b.is_null()) w.remove_body(b);
  });
  EXPECT_GT(boxes_rejected, 50);
  busy.advance();
  expect_finite(w, "after the walk");
}

TEST(AllOrNothing, AddJointOfEveryType) {
  Busy busy;
  World& w = busy.world;
  const BodyId d1 = w.add_body(Busy::cube(Vec3(0.9, 0.3, -0.3)));
  const BodyId d2 = w.add_body(Busy::cube(Vec3(0.9, 0.5, -0.3)));
  auto joint_walk = [&](const char* name, auto def) {
    def.parent = d1;
    def.child = d2;
    return walk(busy, name, def, [&](const auto& d) {
      const JointId j = w.add_joint(d);
      w.step(kDt);
      w.remove_joint(j);
    });
  };
  EXPECT_GT(joint_walk("add_joint(hinge)", HingeDef{}), 50);
  EXPECT_GT(joint_walk("add_joint(slider)", SliderDef{}), 50);
  EXPECT_GT(joint_walk("add_joint(ball)", BallDef{}), 50);
  FixedDef fixed;
  fixed.relative.position = Vec3(0, 0.2, 0);
  EXPECT_GT(joint_walk("add_joint(fixed)", fixed), 50);
}

TEST(AllOrNothing, SettersRemovalsAndStep) {
  Busy busy;
  World& w = busy.world;
  ASSERT_TRUE(w.body_grasp(busy.box.lid).grasped);  // the hands hold the lid: the grasp state is at stake too
  // set_body_pose moves a hard joint's children, set_joint_value places them: every extreme of each argument,
  // on a free body, a jointed parent, a held lid and a hard child.
  for (BodyId target : {busy.a, busy.box.base, busy.box.lid, busy.c}) {
    const Pose pose = w.body_pose(target);
    for (const Pose& p : extremes(pose))
      busy.attempt("set_body_pose", [&] { w.set_body_pose(target, p); }, [&] { w.set_body_pose(target, pose); });
    for (const Vec3& v : extremes(Vec3(Vec3::Zero()))) {
      busy.attempt("set_body_velocity linear", [&] { w.set_body_velocity(target, v, Vec3::Zero()); },
                   [&] { w.set_body_velocity(target, Vec3::Zero(), Vec3::Zero()); });
      busy.attempt("set_body_velocity angular", [&] { w.set_body_velocity(target, Vec3::Zero(), v); },
                   [&] { w.set_body_velocity(target, Vec3::Zero(), Vec3::Zero()); });
    }
  }
  for (JointId j : {busy.box.hinge, busy.hard, busy.soft})
    for (double x : extremes(0.0)) {
      const double value = w.joint_state(j).value;
      busy.attempt("set_joint_value", [&] { w.set_joint_value(j, x); }, [&] { w.set_joint_value(j, value); });
    }
  // Removals the world must refuse whole: a body a joint still uses, stale and foreign ids.
  EXPECT_TRUE(busy.attempt("remove_body (jointed)", [&] { w.remove_body(busy.a); }));
  EXPECT_TRUE(busy.attempt("remove_body (grasped base of the lid's hinge)", [&] { w.remove_body(busy.box.base); }));
  for (BodyId stale : extremes(BodyId{})) {
    EXPECT_TRUE(busy.attempt("remove_body (stale)", [&] { w.remove_body(stale); }));
    EXPECT_TRUE(busy.attempt("remove_hand (stale)", [&] { w.remove_hand(HandId{stale.index, stale.generation}); }));
    EXPECT_TRUE(busy.attempt("remove_joint (stale)", [&] { w.remove_joint(JointId{stale.index, stale.generation}); }));
  }
  // step: every extreme dt, and every extreme in each field of one joint of a frame (hands held on the lid).
  for (double dt : extremes(0.0)) EXPECT_TRUE(busy.attempt("step dt", [&] { w.step(dt); }));
  const std::vector<HandFrame> frames = scenario_frames(busy.box, w, busy.frame);
  for (int joint : {int(kPalm), int(kWrist), 10}) {
    for (const Vec3& p : extremes(frames[0].joints[size_t(joint)].position)) {
      std::vector<HandFrame> bad = frames;
      bad[0].joints[size_t(joint)].position = p;
      busy.attempt("step frame position", [&] { w.step(kDt, busy.inputs(bad)); });
    }
    for (const Quat& q : extremes(frames[1].joints[size_t(joint)].orientation)) {
      std::vector<HandFrame> bad = frames;
      bad[1].joints[size_t(joint)].orientation = q;
      busy.attempt("step frame orientation", [&] { w.step(kDt, busy.inputs(bad)); });
    }
    for (double r : extremes(0.0)) {
      std::vector<HandFrame> bad = frames;
      bad[0].joints[size_t(joint)].radius = r;
      busy.attempt("step frame radius", [&] { w.step(kDt, busy.inputs(bad)); });
    }
  }
  for (Handedness h : extremes(Handedness::Right)) {
    std::vector<HandFrame> bad = frames;
    bad[0].handedness = h;
    EXPECT_TRUE(busy.attempt("step frame handedness", [&] { w.step(kDt, busy.inputs(bad)); }));
  }
  busy.advance();
  expect_finite(w, "after the walk");
  // remove_hand mid-grasp and reset(): accepted, and they end the grasps they imply (Step.* tests the events).
  w.remove_hand(w.hands()[0]);
  w.step(kDt);
  w.reset();
  EXPECT_TRUE(w.bodies().empty() && w.joints().empty());
}
