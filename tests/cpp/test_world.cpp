// The foundation: bodies in a Bullet-backed world, checked against analytic answers.
#include "handsim/tables.h"
#include "handsim/world.h"

#include <gtest/gtest.h>

#include <cstring>
#include <map>
#include <set>
#include <stdexcept>

#include <cmath>
#include <functional>

using namespace handsim;

namespace {

BodyDef box_at(double y, double half = 0.05, double mass = 1.0) {
  BodyDef def;
  def.shape = ShapeDef::box(Vec3::Constant(half));
  def.mass = mass;
  def.pose.position = Vec3(0, y, 0);
  return def;
}

}  // namespace

TEST(World, BoxComesToRestAtHalfHeightAndStays) {
  World world;
  BodyId box = world.add_body(box_at(0.5));
  for (int i = 0; i < 60 * 3; ++i) world.step(1.0 / 60);
  EXPECT_NEAR(world.body_pose(box).position.y(), 0.05, 1e-3);
  for (int i = 0; i < 60 * 10; ++i) {
    world.step(1.0 / 60);
    ASSERT_NEAR(world.body_pose(box).position.y(), 0.05, 1e-3) << "frame " << i;
  }
  EXPECT_LT(world.body_linear_velocity(box).norm(), 1e-3);
}

TEST(World, FreeFallMatchesSemiImplicitEulerAndHalfGTSquared) {
  WorldDef def;
  def.ground = false;
  World world(def);
  BodyId ball = world.add_body(box_at(100.0));
  const double g = 9.81, h = def.fixed_substep;
  const int frames = 120;  // 2 s at 60 Hz, 4 substeps each
  for (int i = 0; i < frames; ++i) world.step(1.0 / 60);
  const int n = frames * 4;
  const double t = n * h;
  // Bullet integrates v += g h, then x += v h: after n substeps the drop is g h^2 n (n + 1) / 2,
  // which differs from the exact g t^2 / 2 by g h t / 2.
  const double drop = 100.0 - world.body_pose(ball).position.y();
  EXPECT_NEAR(drop, g * h * h * n * (n + 1) / 2, 1e-9);
  EXPECT_NEAR(drop, 0.5 * g * t * t, 0.5 * g * h * t + 1e-9);
  EXPECT_NEAR(world.body_linear_velocity(ball).y(), -g * t, 1e-9);
}

TEST(World, DeterminismSameInputsSameHashDifferentInputsDifferentHash) {
  auto run = [](double x0) {
    World world;
    for (int i = 0; i < 5; ++i) {
      BodyDef def = box_at(0.2 + 0.12 * i);
      def.pose.position.x() = x0 + 0.01 * i;
      def.pose.orientation = Quat(Eigen::AngleAxisd(0.3 * i, Vec3(1, 2, 3).normalized()));
      world.add_body(def);
    }
    for (int i = 0; i < 1000; ++i) world.step(1.0 / 60);
    return world.state_hash();
  };
  const uint64_t a = run(0.0);
  EXPECT_EQ(a, run(0.0));
  EXPECT_NE(a, run(1e-6));
}

TEST(World, StaleAndForeignIdsAreRejectedNeverReused) {
  World world, other;
  BodyId a = world.add_body(box_at(1));
  world.remove_body(a);
  BodyId b = world.add_body(box_at(1));
  EXPECT_EQ(a.index, b.index);  // the slot is reused ...
  EXPECT_NE(a.generation, b.generation);  // ... under a new generation
  EXPECT_FALSE(world.contains(a));
  EXPECT_TRUE(world.contains(b));
  try {
    world.body_pose(a);
    FAIL() << "stale id accepted";
  } catch (const Error& e) {
    EXPECT_EQ(e.status(), Status::StaleId);
    EXPECT_EQ(e.argument(), "body");
  }
  other.add_body(box_at(1));
  BodyId foreign = other.bodies().front();
  ASSERT_EQ(foreign.index, b.index);
  EXPECT_FALSE(world.contains(foreign));  // same slot index, but another world's generation salt
  EXPECT_THROW(world.body_pose(foreign), Error);
  EXPECT_THROW(world.remove_body(BodyId{}), Error);
}

TEST(World, KinematicBodyIsMovedOnlyByItsPose) {
  World world;
  BodyDef def = box_at(1.0);
  def.kinematic = true;
  BodyId k = world.add_body(def);
  for (int i = 0; i < 60; ++i) world.step(1.0 / 60);
  EXPECT_EQ(world.body_pose(k).position, Vec3(0, 1.0, 0));
  Pose p;
  p.position = Vec3(0.3, 0.7, -0.2);
  world.set_body_pose(k, p);
  world.step(1.0 / 60);
  EXPECT_EQ(world.body_pose(k).position, p.position);
}

TEST(World, NearUnitQuaternionIsNormalized) {
  World world;
  BodyDef def = box_at(1.0);
  def.pose.orientation = Quat(1.0005, 0, 0, 0);
  BodyId id = world.add_body(def);
  EXPECT_NEAR(world.body_pose(id).orientation.norm(), 1.0, 1e-15);
}

// Every public call with bad arguments: the right status, a message naming the argument, and the world
// unchanged (same state_hash) afterwards.
TEST(World, BadInputTable) {
  World world;
  BodyId box = world.add_body(box_at(0.5));
  BodyId removed = world.add_body(box_at(2.0));
  world.remove_body(removed);
  for (int i = 0; i < 10; ++i) world.step(1.0 / 60);
  const double nan = std::nan("");
  auto with = [](std::function<void(BodyDef&)> edit) {
    BodyDef def = box_at(1);
    edit(def);
    return def;
  };
  struct Case {
    const char* name;
    std::function<void()> call;
    Status status;
    const char* argument;
  };
  Pose far_quat;
  far_quat.orientation = Quat(0.9, 0, 0, 0);
  Pose nan_pose;
  nan_pose.position.x() = nan;
  const std::vector<Case> cases = {
      {"dt zero", [&] { world.step(0); }, Status::InvalidArgument, "dt"},
      {"dt negative", [&] { world.step(-1); }, Status::InvalidArgument, "dt"},
      {"dt nan", [&] { world.step(nan); }, Status::InvalidArgument, "dt"},
      {"dt inf", [&] { world.step(INFINITY); }, Status::InvalidArgument, "dt"},
      {"negative size", [&] { world.add_body(with([](BodyDef& d) { d.shape.half_extents.x() = -1; })); },
       Status::InvalidArgument, "body.shape.half_extents"},
      {"zero radius", [&] { world.add_body(with([](BodyDef& d) { d.shape = ShapeDef::sphere(0); })); },
       Status::InvalidArgument, "body.shape.radius"},
      {"negative mass", [&] { world.add_body(with([](BodyDef& d) { d.mass = -1; })); },
       Status::InvalidArgument, "body.mass"},
      {"nan mass", [&] { world.add_body(with([&](BodyDef& d) { d.mass = nan; })); },
       Status::InvalidArgument, "body.mass"},
      {"nan position", [&] { world.add_body(with([&](BodyDef& d) { d.pose.position.y() = nan; })); },
       Status::InvalidArgument, "body.pose.position"},
      {"non-unit quat", [&] { world.add_body(with([](BodyDef& d) { d.pose.orientation = Quat(0.5, 0, 0, 0); })); },
       Status::InvalidArgument, "body.pose.orientation"},
      {"zero quat", [&] { world.add_body(with([](BodyDef& d) { d.pose.orientation = Quat(0, 0, 0, 0); })); },
       Status::InvalidArgument, "body.pose.orientation"},
      {"nan velocity", [&] { world.add_body(with([&](BodyDef& d) { d.linear_velocity.z() = nan; })); },
       Status::InvalidArgument, "body.linear_velocity"},
      {"negative friction", [&] { world.add_body(with([](BodyDef& d) { d.friction = -0.1; })); },
       Status::InvalidArgument, "body.friction"},
      {"hull too small", [&] { world.add_body(with([](BodyDef& d) { d.shape = ShapeDef::convex_hull({Vec3::Zero()}); })); },
       Status::InvalidArgument, "body.shape.points"},
      {"mesh bad index", [&] {
         world.add_body(with([](BodyDef& d) {
           d.mass = 0;
           d.shape = ShapeDef::triangle_mesh({Vec3(0, 0, 0), Vec3(1, 0, 0), Vec3(0, 0, 1)}, {0, 1, 7});
         }));
       }, Status::InvalidArgument, "body.shape.indices"},
      {"dynamic mesh", [&] {
         world.add_body(with([](BodyDef& d) {
           d.shape = ShapeDef::triangle_mesh({Vec3(0, 0, 0), Vec3(1, 0, 0), Vec3(0, 0, 1)}, {0, 1, 2});
         }));
       }, Status::InvalidArgument, "body.mass"},
      {"stale pose", [&] { world.body_pose(removed); }, Status::StaleId, "body"},
      {"stale set pose", [&] { world.set_body_pose(removed, Pose()); }, Status::StaleId, "body"},
      {"stale remove", [&] { world.remove_body(removed); }, Status::StaleId, "body"},
      {"null id", [&] { world.body_linear_velocity(BodyId{}); }, Status::StaleId, "body"},
      {"set pose nan", [&] { world.set_body_pose(box, nan_pose); }, Status::InvalidArgument, "pose.position"},
      {"set pose bad quat", [&] { world.set_body_pose(box, far_quat); }, Status::InvalidArgument, "pose.orientation"},
      {"set velocity nan", [&] { world.set_body_velocity(box, Vec3(nan, 0, 0), Vec3::Zero()); },
       Status::InvalidArgument, "linear"},
      {"set angular inf", [&] { world.set_body_velocity(box, Vec3::Zero(), Vec3(0, INFINITY, 0)); },
       Status::InvalidArgument, "angular"},
  };
  const uint64_t before = world.state_hash();
  const size_t bodies_before = world.bodies().size();
  for (const Case& c : cases) {
    try {
      c.call();
      ADD_FAILURE() << c.name << ": no error";
    } catch (const Error& e) {
      EXPECT_EQ(e.status(), c.status) << c.name << ": " << e.what();
      EXPECT_EQ(e.argument(), c.argument) << c.name << ": " << e.what();
      EXPECT_EQ(std::string(e.what()).rfind(c.argument, 0), 0u) << c.name << ": " << e.what();
    }
    EXPECT_EQ(world.state_hash(), before) << c.name;
    EXPECT_EQ(world.bodies().size(), bodies_before) << c.name;
  }
}

TEST(World, BadWorldDef) {
  WorldDef def;
  def.fixed_substep = 0;
  EXPECT_THROW(World{def}, Error);
  def = WorldDef();
  def.gravity.x() = std::nan("");
  EXPECT_THROW(World{def}, Error);
  def = WorldDef();
  def.max_substeps = 0;
  EXPECT_THROW(World{def}, Error);
}

TEST(World, FlatDropLandsFlatWithoutDrift) {
  for (double mass : {0.05, 0.2, 1.0, 10.0}) {
    World world;
    BodyId box = world.add_body(box_at(0.5, 0.05, mass));
    for (int i = 0; i < 120; ++i) world.step(1.0 / 60);
    const Pose p = world.body_pose(box);
    EXPECT_NEAR(p.position.y(), 0.05, 1e-3) << "mass " << mass;
    EXPECT_LT(p.position.head<1>().norm() + std::abs(p.position.z()), 1e-3) << "mass " << mass;
    // Resting flat: the box's up axis is the world's (the sequential-impulse solver may leave a small yaw).
    const double tilt = std::acos(std::min(1.0, (p.orientation * Vec3::UnitY()).y()));
    EXPECT_LT(tilt, 1e-4) << "mass " << mass;
    EXPECT_LT(p.orientation.angularDistance(Quat::Identity()), 1e-2) << "mass " << mass;
  }
}

// --- the scene-driven pipeline: lazy particles, the contact prefilter, threaded render skinning ---

namespace {

HandFrame flat_hand_at(const Vec3& palm) { return make_hand_frame(Handedness::Right, Pose{palm, Quat::Identity()}); }

}  // namespace

TEST(LeanPipeline, FarHandSkipsParticleSkinningAndReadsStayExact) {
  World w(WorldDef{});
  BodyDef box;
  box.shape = ShapeDef::box(Vec3(0.05, 0.05, 0.05));
  box.pose.position = Vec3(0, 0.05, 0);
  w.add_body(box);
  const HandId hand = w.add_hand(HandDef{});
  const HandFrame far = flat_hand_at(Vec3(2, 1.5, 2));
  const StepReport report = w.step(1.0 / 60, {{hand, far}});
  EXPECT_EQ(report.stage(Stage::Skinning).work, 1);      // one tracked hand ...
  EXPECT_EQ(report.stage(Stage::Skinning).particles, 0);  // ... far: no particle skinned
  EXPECT_EQ(report.stage(Stage::Contacts).skip, SkipReason::NoHandNearBody);
  // Reading the particles skins them now, with the step's arithmetic: the same bits as pose_hand.
  HandState s;
  pose_hand(w.hand_model(hand), far, s);
  const Eigen::Matrix3Xd tracked = w.hand_particles(hand, false), deformed = w.hand_particles(hand, true);
  ASSERT_EQ(tracked.cols(), s.tracked_positions.cols());
  EXPECT_EQ(std::memcmp(tracked.data(), s.tracked_positions.data(), sizeof(double) * tracked.size()), 0);
  EXPECT_EQ(std::memcmp(deformed.data(), s.tracked_positions.data(), sizeof(double) * tracked.size()), 0);
}

TEST(LeanPipeline, ContactPrefilterFindsEveryContact) {
  // A hand pressed into a static box: the deformation the world computes from its prefiltered contacts must
  // equal the one from collide_particles over every particle.
  World w(WorldDef{});
  BodyDef box;
  box.shape = ShapeDef::box(Vec3(0.2, 0.1, 0.2));
  box.mass = 0;
  box.pose.position = Vec3(0, -0.1, -0.05);
  const BodyId body = w.add_body(box);
  const HandId hand = w.add_hand(HandDef{});
  w.step(1.0 / 60, {{hand, flat_hand_at(Vec3(0, 0.3, 0))}});
  const double lowest = w.hand_particles(hand, false).row(1).minCoeff() - 0.3;
  const HandFrame press = flat_hand_at(Vec3(0, -lowest - 0.01, 0));
  w.step(1.0 / 60, {{hand, press}});
  const HandModel& m = w.hand_model(hand);
  HandState s;
  pose_hand(m, press, s);
  std::vector<ParticleContact> all;
  collide_particles(s.tracked_positions, m.particle_radius, box.shape, box.pose, all);
  ASSERT_GT(all.size(), 10u);
  EXPECT_EQ(w.body_contact_count(body, hand), int(all.size()));
  deform_particles(m, s, all);
  const Eigen::Matrix3Xd deformed = w.hand_particles(hand, true);
  EXPECT_EQ(std::memcmp(deformed.data(), s.deformed_positions.data(), sizeof(double) * deformed.size()), 0);
}

TEST(LeanPipeline, ThreadedRenderSkinningIsBitIdentical) {
  Eigen::Matrix3Xd out[2];
  for (int threads : {1, 2}) {
    WorldDef def;
    def.render_threads = threads;
    World w(def);
    BodyDef box;
    box.shape = ShapeDef::box(Vec3(0.2, 0.1, 0.2));
    box.mass = 0;
    box.pose.position = Vec3(0, -0.1, -0.05);
    w.add_body(box);
    const HandId hand = w.add_hand(HandDef{});
    w.step(1.0 / 60, {{hand, flat_hand_at(Vec3(0, 0.02, 0))}});  // pressing: the render deformation runs too
    out[threads - 1] = w.hand_render_vertices(hand);
  }
  ASSERT_EQ(out[0].cols(), out[1].cols());
  EXPECT_EQ(std::memcmp(out[0].data(), out[1].data(), sizeof(double) * out[0].size()), 0);
  WorldDef bad;
  bad.render_threads = 0;
  EXPECT_THROW(World{bad}, Error);
}

// The enum table (handsim/enum_table.h) declares the C++ enums; each enum's rows must number its values 0..n-1
// with names used once, since the C ABI, C# and Python index and name values by those rows.
TEST(Tables, EveryEnumIsNumberedFromZeroWithUniqueNames) {
  std::map<std::string, std::vector<const EnumValue*>> by_type;
  for (const EnumValue& row : kEnumValues) by_type[row.type].push_back(&row);
  EXPECT_EQ(by_type.size(), 16u);  // PushModel the 16th
  for (const auto& [type, rows] : by_type) {
    std::set<std::string> names, uppers, constants;
    for (size_t i = 0; i < rows.size(); ++i) {
      EXPECT_EQ(rows[i]->value, int(i)) << type << "::" << rows[i]->name;
      EXPECT_TRUE(names.insert(rows[i]->name).second) << type << "::" << rows[i]->name;
      EXPECT_TRUE(uppers.insert(rows[i]->upper).second) << type << "::" << rows[i]->upper;
      EXPECT_TRUE(constants.insert(rows[i]->constant).second) << rows[i]->constant;
      EXPECT_EQ(std::string(rows[i]->constant).rfind("HANDSIM_", 0), 0u) << rows[i]->constant;
    }
  }
  // The value issue 21 found missing from every binding.
  EXPECT_EQ(int(EventReason::HandRemoved), 4);
  EXPECT_EQ(by_type["EventReason"].back()->constant, std::string("HANDSIM_REASON_HAND_REMOVED"));
}

// Every mirrored def has rows (the field count itself is a static_assert in core/src/tables.cpp).
TEST(Tables, EveryMirroredDefHasRows) {
  for (const MirroredDef& def : kMirroredDefs) {
    int rows = 0;
    for (const DefField& field : kDefFields) rows += std::string(field.def) == def.def;
    EXPECT_GT(rows, 0) << def.def;
  }
  int world_rows = 0;
  for (const DefField& field : kDefFields) world_rows += std::string(field.def) == "WorldDef";
  EXPECT_EQ(world_rows, 15);  // paper_pipeline and render_threads included, which the C struct once lacked; skin_*, push_model
}
