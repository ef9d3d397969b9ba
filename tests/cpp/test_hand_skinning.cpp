// Procedural mesh, skin weights and linear blend skinning (eq. 1).
#include "handsim/hand.h"
#include "skinning.h"

#include <gtest/gtest.h>

#include <cstring>
#include <map>
#include <random>

using namespace handsim;

namespace {

const HandModel& right_model() {
  static const HandModel m = build_hand_model(HandDef{});
  return m;
}

Pose some_pose() {
  Pose p;
  p.position = Vec3(0.2, 1.0, -0.3);
  p.orientation = Quat(Eigen::AngleAxisd(1.1, Vec3(0.3, -1, 0.5).normalized()));
  return p;
}

bool weighted_to(const SkinnedMesh& m, int v, int first_joint, int last_joint) {
  for (int k = 0; k < 4; ++k)
    if (m.weights(k, v) > 0 && m.bones(k, v) >= first_joint && m.bones(k, v) <= last_joint) return true;
  return false;
}

}  // namespace

TEST(HandMesh, ClosedOutwardAndNearTheRequestedSize) {
  for (Handedness h : {Handedness::Right, Handedness::Left}) {
    HandDef def;
    def.handedness = h;
    HandModel m = build_hand_model(def);
    const SkinnedMesh& mesh = m.mesh;
    EXPECT_NEAR(double(m.vertex_count()), 39000.0, 39000.0 * 0.05);
    // Closed and consistently oriented: every directed edge once, and its reverse once.
    std::map<std::pair<int, int>, int> edges;
    for (size_t t = 0; t < mesh.triangles.size(); t += 3)
      for (int e = 0; e < 3; ++e) edges[{mesh.triangles[t + e], mesh.triangles[t + (e + 1) % 3]}]++;
    int bad = 0;
    for (auto& [e, c] : edges)
      if (c != 1 || edges.count({e.second, e.first}) == 0 || edges.at({e.second, e.first}) != 1) ++bad;
    EXPECT_EQ(bad, 0);
    double vol = 0;
    for (size_t t = 0; t < mesh.triangles.size(); t += 3)
      vol += mesh.positions.col(mesh.triangles[t])
                 .dot(mesh.positions.col(mesh.triangles[t + 1]).cross(mesh.positions.col(mesh.triangles[t + 2])));
    vol /= 6;
    EXPECT_GT(vol, 150e-6);  // a hand is a few hundred cm^3 (parts overlap, so this overcounts a little)
    EXPECT_LT(vol, 600e-6);
    for (int v = 0; v < m.vertex_count(); ++v) {
      EXPECT_NEAR(mesh.weights.col(v).sum(), 1.0, 1e-12);
      EXPECT_GE(mesh.weights.col(v).minCoeff(), 0.0);
    }
    EXPECT_NO_THROW(validate_skinned_mesh(mesh, "mesh"));
  }
}

TEST(HandMesh, Deterministic) {
  HandFrame bind = bind_frame(Handedness::Right);
  SkinnedMesh a = make_hand_mesh(bind, 5000), b = make_hand_mesh(bind, 5000);
  EXPECT_EQ(a.positions, b.positions);
  EXPECT_EQ(a.triangles, b.triangles);
  EXPECT_EQ(a.weights, b.weights);
}

TEST(HandSkinning, BindPoseGivesTheBindMesh) {
  const HandModel& m = right_model();
  HandState s;
  pose_hand(m, m.bind, s);
  Eigen::Matrix3Xd out;
  skin_render(m, s, out);
  EXPECT_LE((out - m.mesh.positions).cwiseAbs().maxCoeff(), 1e-15);
  EXPECT_LE((s.tracked_positions - m.particle_bind).cwiseAbs().maxCoeff(), 1e-15);
  EXPECT_TRUE(s.tracked);
}

TEST(HandSkinning, RigidMotionOfAllJointsMovesTheMeshRigidly) {
  const HandModel& m = right_model();
  const Pose T = some_pose();
  HandFrame f = m.bind;
  for (JointPose& j : f.joints) {
    j.position = T.transform(j.position);
    j.orientation = (T.orientation * j.orientation).normalized();
  }
  HandState s;
  pose_hand(m, f, s);
  Eigen::Matrix3Xd out;
  skin_render(m, s, out);
  double worst = 0;
  for (int v = 0; v < m.vertex_count(); ++v)
    worst = std::max(worst, (out.col(v) - T.transform(m.mesh.positions.col(v))).norm());
  EXPECT_LE(worst, 1e-12);
  for (int p = 0; p < m.particle_count(); ++p)
    EXPECT_LE((s.tracked_positions.col(p) - T.transform(m.particle_bind.col(p))).norm(), 1e-12);
  // Bounds enclose the particle spheres.
  for (int p = 0; p < m.particle_count(); ++p) {
    EXPECT_TRUE((s.tracked_positions.col(p).array() - m.particle_radius >= s.bounds_lo.array() - 1e-15).all());
    EXPECT_TRUE((s.tracked_positions.col(p).array() + m.particle_radius <= s.bounds_hi.array() + 1e-15).all());
  }
}

TEST(HandSkinning, BendingOneFingerMovesOnlyItsVertices) {
  const HandModel& m = right_model();
  HandPoseParams p;
  p.curl[1] = 0.8;  // index only
  HandFrame f = make_hand_frame(Handedness::Right, Pose{}, p);
  HandState s;
  pose_hand(m, f, s);
  Eigen::Matrix3Xd out;
  skin_render(m, s, out);
  int moved_index = 0, index_vertices = 0;
  for (int v = 0; v < m.vertex_count(); ++v) {
    double d = (out.col(v) - m.mesh.positions.col(v)).norm();
    if (weighted_to(m.mesh, v, kIndexProximal, kIndexTip)) {
      ++index_vertices;
      if (d > 1e-4) ++moved_index;
    } else {
      EXPECT_LE(d, 1e-12) << "vertex " << v;
    }
  }
  EXPECT_GT(index_vertices, 3000);
  EXPECT_GT(moved_index, index_vertices * 9 / 10);
}

TEST(HandSkinning, GroupedRenderPathEqualsPerVertexPath) {
  const HandModel& m = right_model();
  HandPoseParams p;
  p.curl = {0.3, 0.5, 0.7, 0.9, 1.0};
  p.thumb_opposition = 0.5;
  p.spread = 0.4;
  HandFrame f = make_hand_frame(Handedness::Right, some_pose(), p);
  // Perturb the metacarpals so the palm blends (4 influences) are exercised.
  f.joints[kRingMetacarpal].position += Vec3(0.004, -0.003, 0.002);
  f.joints[kThumbMetacarpal].orientation =
      (Quat(Eigen::AngleAxisd(0.3, Vec3::UnitX())) * f.joints[kThumbMetacarpal].orientation).normalized();
  HandState s;
  pose_hand(m, f, s);
  Eigen::Matrix3Xd grouped, naive;
  skin_render(m, s, grouped);
  skin_points(m.mesh.positions, m.mesh.bones, m.mesh.weights, s.bones, naive);
  EXPECT_LE((grouped - naive).cwiseAbs().maxCoeff(), 1e-13);
  int four = 0;
  for (const SkinGroup& g : m.skin.groups) four += g.count == 4 ? g.end - g.begin : 0;
  EXPECT_GT(four, 0);
}

// The particles go through the grouped path with their vertices' render weights: a tracked particle is its
// render vertex bit for bit, and both stay within rounding of the per-point formula.
TEST(HandSkinning, GroupedParticlesAreTheirRenderVerticesBitForBit) {
  for (ParticleSampling sampling : {ParticleSampling::Random, ParticleSampling::Even}) {
    HandDef def;
    def.sampling = sampling;
    def.particle_count = 3000;
    const HandModel m = build_hand_model(def);
    EXPECT_LE(m.particle_skin.groups.size(), m.skin.groups.size() + size_t(m.particle_count() / kMaxParticleRun));
    for (int trial = 0; trial < 6; ++trial) {
      HandPoseParams p;
      p.curl = {0.15 * trial, 0.1 * trial, 0.2 * trial, 0.05 * trial, 0.17 * trial};
      p.thumb_opposition = 0.1 * trial;
      p.spread = 0.3 - 0.1 * trial;
      HandFrame f = make_hand_frame(Handedness::Right, some_pose(), p);
      f.joints[kRingMetacarpal].position += Vec3(0.001 * trial, -0.003, 0.002);
      if (trial % 2) f.joints[kIndexDistal].valid = false;
      HandState s;
      pose_hand(m, f, s);
      Eigen::Matrix3Xd render, naive;
      skin_render(m, s, render);
      skin_points(m.particle_bind, m.particle_bones, m.particle_weights, s.bones, naive);
      ASSERT_EQ(naive.cols(), s.tracked_positions.cols());
      for (int q = 0; q < m.particle_count(); ++q) {
        const Vec3 a = s.tracked_positions.col(q), b = render.col(m.particle_vertex[q]);
        ASSERT_EQ(std::memcmp(a.data(), b.data(), sizeof(double) * 3), 0) << "trial " << trial << " particle " << q;
      }
      EXPECT_LE((naive - s.tracked_positions).cwiseAbs().maxCoeff(), 1e-15) << "trial " << trial;
    }
  }
}

// The multi-threaded render skinning splits the groups between threads; each vertex is still computed by the
// same code, so every thread count gives the same bits as one thread.
TEST(HandSkinning, ThreadedRenderSkinningIsBitIdenticalToOneThread) {
  const HandModel& m = right_model();
  HandPoseParams p;
  p.curl = {0.2, 0.4, 0.6, 0.8, 0.9};
  HandState s;
  pose_hand(m, make_hand_frame(Handedness::Right, some_pose(), p), s);
  Eigen::Matrix3Xd one;
  skin_groups(m, s.bones, one, 1);
  for (int threads : {2, 3, 7, 64}) {
    Eigen::Matrix3Xd many = Eigen::Matrix3Xd::Constant(3, 5, 42.0);  // wrong size on purpose: resized
    skin_groups(m, s.bones, many, threads);
    ASSERT_EQ(many.cols(), one.cols());
    EXPECT_EQ(std::memcmp(many.data(), one.data(), sizeof(double) * one.size()), 0) << threads << " threads";
  }
}

// The coarse box from the bones alone holds every particle sphere, for any pose (it decides whether a hand
// skips skinning its particles, so it must never be too small).
TEST(HandSkinning, CoarseBoundsHoldEveryParticle) {
  const HandModel& m = right_model();
  const HandReach reach = build_hand_reach(m);
  for (int trial = 0; trial < 8; ++trial) {
    HandPoseParams p;
    p.curl = {0.12 * trial, 0.13 * trial, 0.1 * trial, 0.11 * trial, 0.125 * trial};
    p.thumb_opposition = 0.12 * trial;
    p.spread = 0.5 - 0.15 * trial;
    HandFrame f = make_hand_frame(Handedness::Right, some_pose(), p);
    if (trial % 3 == 0) f.joints[kMiddleIntermediate].valid = false;
    HandState s;
    pose_hand(m, f, s);
    Vec3 lo, hi;
    coarse_particle_bounds(reach, s.bones, lo, hi);
    EXPECT_TRUE((lo.array() <= s.bounds_lo.array()).all()) << "trial " << trial;
    EXPECT_TRUE((hi.array() >= s.bounds_hi.array()).all()) << "trial " << trial;
    EXPECT_LT((hi - lo).maxCoeff(), 0.6);  // and still a hand-sized box, or it would cull nothing
  }
}

// The coarse box grown by the groups' excess holds every group's coarse box grown by the particle radius, near
// the origin and a kilometre away (the hand's bounds when no body is within reach of any group: they must
// leave out no body a group could reach).
TEST(HandSkinning, CoarseBoundsHeldGroupBoxesHoldEveryGroupBox) {
  const HandModel& m = right_model();
  const HandReach reach = build_hand_reach(m);
  EXPECT_GT(reach.group_excess, 0.0);
  EXPECT_LT(reach.group_excess, 0.05);  // a hand-sized growth, or the bounds would cull nothing
  for (int trial = 0; trial < 16; ++trial) {
    HandPoseParams p;
    p.curl = {0.06 * trial, 0.065 * trial, 0.05 * trial, 0.055 * trial, 0.0625 * trial};
    p.thumb_opposition = 0.06 * trial;
    p.spread = 0.5 - 0.075 * trial;
    Pose at = some_pose();
    if (trial % 2) at.position += Vec3(1e3, -7e2, 3e2);
    HandFrame f = make_hand_frame(Handedness::Right, at, p);
    if (trial % 3 == 0) f.joints[kMiddleIntermediate].valid = false;
    HandState s;
    pose_hand(m, f, s);
    Vec3 lo, hi;
    coarse_particle_bounds(reach, s.bones, lo, hi);
    hold_group_boxes(reach, lo, hi);
    for (size_t g = 0; g < m.particle_skin.groups.size(); ++g) {
      double box[6];
      coarse_bounds(m.particle_skin.groups[g], reach.group_centre[g], reach.group_radius[g], s.bones, box);
      for (int d = 0; d < 3; ++d) {
        EXPECT_LE(lo[d], box[d] - m.particle_radius) << "trial " << trial << " group " << g;
        EXPECT_GE(hi[d], box[3 + d] + m.particle_radius) << "trial " << trial << " group " << g;
      }
    }
  }
}

TEST(HandSkinning, UntrackedFrameKeepsTheLastPose) {
  const HandModel& m = right_model();
  HandState s;
  pose_hand(m, make_hand_frame(Handedness::Right, some_pose()), s);
  Eigen::Matrix3Xd before = s.tracked_positions;
  HandFrame lost = m.bind;
  lost.joints[kWrist].valid = false;
  lost.joints[kWrist].position.setConstant(std::nan(""));
  pose_hand(m, lost, s);
  EXPECT_FALSE(s.tracked);
  EXPECT_EQ(s.tracked_positions, before);
}

TEST(HandSkinning, InvalidFingerJointFollowsItsParent) {
  const HandModel& m = right_model();
  HandPoseParams p;
  p.curl[2] = 0.6;
  HandFrame f = make_hand_frame(Handedness::Right, some_pose(), p);
  HandFrame g = f;
  g.joints[kMiddleDistal].valid = false;
  g.joints[kMiddleDistal].position.setConstant(std::nan(""));
  HandState s;
  pose_hand(m, g, s);
  EXPECT_TRUE(s.tracked_positions.allFinite());
  EXPECT_TRUE(s.bones[kMiddleDistal].isApprox(s.bones[kMiddleIntermediate], 1e-15));
}

// The step's bones (four at a time where the CPU has AVX2) are the one-bone-at-a-time formula's, bit for bit:
// random joint positions and orientations (unit and not, near and far from the origin), some joints invalid
// (their numbers garbage, NaN included), for both hands.
TEST(HandSkinning, BonesAreTheScalarFormulasBitForBit) {
  std::mt19937_64 rng(25);
  std::normal_distribution<double> gauss(0, 1);
  std::uniform_real_distribution<double> uniform(-1, 1);
  int compared = 0;
  for (Handedness hand : {Handedness::Right, Handedness::Left}) {
    HandDef def;
    def.handedness = hand;
    const HandModel m = build_hand_model(def);
    for (int t = 0; t < 2000; ++t) {
      HandFrame f;
      f.handedness = hand;
      for (int j = 0; j < kHandJointCount; ++j) {
        JointPose& jp = f.joints[j];
        jp.position = Vec3(uniform(rng), uniform(rng), uniform(rng)) * (t % 5 == 0 ? 1e3 : 1.0);
        jp.orientation = Quat(gauss(rng), gauss(rng), gauss(rng), gauss(rng));
        jp.orientation.normalize();
        if (t % 3) jp.orientation.coeffs() *= 1 + 1e-6 * uniform(rng);  // as a tracker's, near unit
        jp.valid = j == kPalm || j == kWrist || t % 4 != 1 || uniform(rng) > 0;
        if (!jp.valid && j % 2) jp.orientation.coeffs().setConstant(std::nan(""));
      }
      std::array<BoneTransform, kHandJointCount> fast, scalar;
      compute_bone_transforms(m, f, fast);
      compute_bone_transforms_scalar(m, f, scalar);
      ASSERT_EQ(std::memcmp(fast.data(), scalar.data(), sizeof fast), 0) << "frame " << t;
      ++compared;
    }
  }
  EXPECT_EQ(compared, 4000);
}

// The hand's coarse bounds (four bones at a time where the CPU has AVX2) are the one-bone-at-a-time loop's, bit
// for bit, for random bones near and far from the origin, with the model's reach and with some bones moving no
// particle (reach < 0).
TEST(HandSkinning, CoarseBoundsAreTheScalarLoopsBitForBit) {
  const HandModel m = build_hand_model(HandDef{});
  HandReach reach = build_hand_reach(m);
  std::mt19937_64 rng(25);
  std::normal_distribution<double> gauss(0, 1);
  std::uniform_real_distribution<double> uniform(-1, 1);
  for (int t = 0; t < 3000; ++t) {
    std::array<BoneTransform, kHandJointCount> bones;
    for (BoneTransform& b : bones) {
      b.leftCols<3>() = Quat(gauss(rng), gauss(rng), gauss(rng), gauss(rng)).normalized().toRotationMatrix();
      b.col(3) = Vec3(uniform(rng), uniform(rng), uniform(rng)) * (t % 5 == 0 ? 1e4 : 1.0);
    }
    HandReach r = reach;
    if (t % 2)
      for (double& x : r.reach) x = uniform(rng) < -0.5 ? -1.0 : x;
    fill_reach_lanes(r);
    Vec3 lo, hi, lo_scalar, hi_scalar;
    coarse_particle_bounds(r, bones, lo, hi);
    coarse_particle_bounds_scalar(r, bones, lo_scalar, hi_scalar);
    ASSERT_EQ(std::memcmp(lo.data(), lo_scalar.data(), sizeof(Vec3)), 0) << "bones " << t;
    ASSERT_EQ(std::memcmp(hi.data(), hi_scalar.data(), sizeof(Vec3)), 0) << "bones " << t;
  }
}

TEST(HandSkinning, SuppliedMeshIsValidatedAndUsable) {
  HandFrame bind = bind_frame(Handedness::Right);
  SkinnedMesh mesh = make_hand_mesh(bind, 3000);
  HandDef def;
  def.particle_count = 300;
  HandModel m = build_hand_model(def, mesh, bind);
  EXPECT_EQ(m.particle_count(), 300);
  EXPECT_EQ(m.vertex_count(), mesh.positions.cols());
  for (int i = 0; i < m.vertex_count(); ++i)
    ASSERT_EQ(m.mesh.positions.col(i), mesh.positions.col(m.source_vertex[i]));

  auto expect_error = [&](const SkinnedMesh& bad, const std::string& arg) {
    try {
      build_hand_model(def, bad, bind);
      FAIL() << "expected an error on " << arg;
    } catch (const Error& e) {
      EXPECT_EQ(e.argument(), arg) << e.what();
    }
  };
  SkinnedMesh bad = mesh;
  bad.positions(1, 17) = std::nan("");
  expect_error(bad, "mesh.positions");
  bad = mesh;
  bad.bones(0, 5) = 26;
  expect_error(bad, "mesh.bones");
  bad = mesh;
  bad.weights(0, 9) *= 0.5;
  expect_error(bad, "mesh.weights");
  bad = mesh;
  bad.weights(1, 9) = -0.1;
  expect_error(bad, "mesh.weights");
  bad = mesh;
  bad.triangles[4] = int(mesh.positions.cols());
  expect_error(bad, "mesh.triangles");
  bad = mesh;
  bad.weights.conservativeResize(4, mesh.weights.cols() - 1);
  expect_error(bad, "mesh.weights");
  HandFrame bad_bind = bind;
  bad_bind.joints[4].valid = false;
  try {
    build_hand_model(def, mesh, bad_bind);
    FAIL();
  } catch (const Error& e) {
    EXPECT_EQ(e.argument(), "bind.joints[4]");
  }
}

TEST(HandSkinning, BadFramesAreRejected) {
  const HandModel& m = right_model();
  HandState s;
  HandFrame f = m.bind;
  f.joints[kIndexDistal].orientation.coeffs() << 0.1, 0.2, 0.3, 0.4;
  try {
    pose_hand(m, f, s);
    FAIL();
  } catch (const Error& e) {
    EXPECT_EQ(e.argument(), "frame.joints[9].orientation");
  }
  f = m.bind;
  f.handedness = Handedness::Left;
  EXPECT_THROW(pose_hand(m, f, s), Error);
}
