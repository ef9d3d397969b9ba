#include "grasp.h"
#include "skinning.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cmath>
#include <random>

using namespace handsim;

namespace {

bool brute_force(const std::vector<Vec3>& d, double c, const std::vector<int>* parts = nullptr) {
  for (size_t i = 0; i < d.size(); ++i)
    for (size_t j = i + 1; j < d.size(); ++j)
      if ((!parts || (*parts)[i] != (*parts)[j]) && d[i].dot(d[j]) < c) return true;
  return false;
}

Vec3 random_unit(std::mt19937_64& gen) {
  std::normal_distribution<double> n;
  return Vec3(n(gen), n(gen), n(gen)).normalized();
}

// Directions within `half_angle` of `axis`.
std::vector<Vec3> cone(std::mt19937_64& gen, const Vec3& axis, double half_angle, int n) {
  std::uniform_real_distribution<double> u(0, 1);
  Vec3 a = axis.normalized(), b = a.unitOrthogonal(), c = a.cross(b);
  std::vector<Vec3> d;
  for (int i = 0; i < n; ++i) {
    double th = half_angle * std::sqrt(u(gen)), ph = 2 * M_PI * u(gen);
    d.push_back(std::cos(th) * a + std::sin(th) * (std::cos(ph) * b + std::sin(ph) * c));
  }
  return d;
}

GraspInput frame(bool opposing, int contacts, bool tracked = true, double dt = 1.0 / 60) {
  return {opposing, contacts, tracked, dt};
}

}  // namespace

// ---------------------------------------------------------------------------------------------------------
// opposing_contacts

TEST(OpposingContacts, PinchFromOppositeSides) {
  Vec3 thumb(1, 0, 0), index = Vec3(-1, 0.2, 0).normalized();
  EXPECT_TRUE(opposing_contacts({thumb, index}));
  EXPECT_TRUE(opposing_contacts({thumb, index}, kOpposingCos));
  // ~100 degrees apart: opposing under the literal +0.7 reading only.
  Vec3 side = Vec3(-0.17, 1, 0).normalized();
  EXPECT_FALSE(opposing_contacts({thumb, side}));
  EXPECT_TRUE(opposing_contacts({thumb, side}, kPaperLiteralCos));
  // ~30 degrees apart: neither reading.
  Vec3 near = Vec3(1, 0.58, 0).normalized();
  EXPECT_FALSE(opposing_contacts({thumb, near}, kOpposingCos));
  EXPECT_FALSE(opposing_contacts({thumb, near}, kPaperLiteralCos));
}

// GraspSettings::across_parts: a pair of one rigid part (the edge of a hand draped over a box) does not count.
TEST(OpposingContacts, AcrossPartsNeedsTwoParts) {
  const std::vector<Vec3> d = {Vec3::UnitX(), -Vec3::UnitX(), Vec3::UnitY()};
  EXPECT_FALSE(opposing_across_parts(d, {0, 0, 7}));
  EXPECT_TRUE(opposing_across_parts(d, {0, 4, 4}));
  EXPECT_FALSE(opposing_across_parts({Vec3::UnitY(), Vec3::UnitY()}, {0, 4}));
  EXPECT_THROW(opposing_across_parts(d, {0, 4}), Error);
}

// squeezing_pair: two different fingers never squeeze (they flex in parallel); the thumb and the palm oppose every finger, and one
// finger's phalanges oppose each other (a finger hooked round an edge).
TEST(OpposingContacts, DifferentFingersDoNotSqueeze) {
  EXPECT_FALSE(can_squeeze(kIndexDistal, kMiddleDistal));
  EXPECT_FALSE(can_squeeze(kRingIntermediate, kLittleProximal));
  EXPECT_FALSE(can_squeeze(kPalm, kPalm));
  EXPECT_TRUE(can_squeeze(kIndexIntermediate, kIndexDistal));
  EXPECT_TRUE(can_squeeze(kThumbDistal, kLittleDistal));
  EXPECT_TRUE(can_squeeze(kPalm, kMiddleDistal));
  EXPECT_TRUE(can_squeeze(kPalm, kThumbProximal));
  const std::vector<Vec3> d = {Vec3::UnitX(), -Vec3::UnitX()};
  EXPECT_TRUE(opposing_across_parts(d, {kIndexDistal, kRingDistal}));  // eq. 3 across parts: two parts suffice
  EXPECT_FALSE(squeezing_pair(d, {kIndexDistal, kRingDistal}, {0.01, 0.01}, kOpposingCos, 0.01));
  EXPECT_TRUE(squeezing_pair(d, {kIndexDistal, kThumbDistal}, {0.01, 0.01}, kOpposingCos, 0.01));
  EXPECT_TRUE(squeezing_pair(d, {kIndexDistal, kIndexProximal}, {0.01, 0.01}, kOpposingCos, 0.01));
}

// squeezing_pair: an opposing pair of two parts whose inward motions sum to at least `needed`.
TEST(OpposingContacts, SqueezingPairNeedsInwardMotionOfAnOpposingPair) {
  const std::vector<Vec3> d = {Vec3::UnitX(), -Vec3::UnitX(), Vec3::UnitY()};
  const std::vector<int> parts = {kThumbDistal, kIndexDistal, kMiddleDistal};
  EXPECT_TRUE(squeezing_pair(d, parts, {0.006, 0.005, 0.0}, kOpposingCos, 0.01));
  EXPECT_FALSE(squeezing_pair(d, parts, {0.006, 0.003, 0.0}, kOpposingCos, 0.01));
  EXPECT_TRUE(squeezing_pair(d, parts, {0.02, 0.0, 0.0}, kOpposingCos, 0.01));  // one side may do all the moving
  EXPECT_FALSE(squeezing_pair(d, parts, {0.004, 0.0, 0.02}, kOpposingCos, 0.01));  // the pair that moved does not oppose
  EXPECT_FALSE(squeezing_pair(d, {kThumbDistal, kThumbDistal, kMiddleDistal}, {0.006, 0.005, 0.0}, kOpposingCos, 0.01));
  EXPECT_TRUE(squeezing_pair(d, {}, {0.006, 0.005, 0.0}, kOpposingCos, 0.01));  // no parts: any pair
  EXPECT_THROW(squeezing_pair(d, parts, {0.1, 0.1}, kOpposingCos, 0.01), Error);
  EXPECT_THROW(squeezing_pair(d, {1, 2}, {0.1, 0.1, 0.1}, kOpposingCos, 0.01), Error);
  EXPECT_THROW(squeezing_pair(d, parts, {0.1, 0.1, 0.1}, kOpposingCos, NAN), Error);
}

// ArticulationHistory::inward: a curling index fingertip moved inwards by about how far it moved relative to the palm;
// the same hand moved and turned as a whole, or a palm particle, moved by nothing.
TEST(ArticulationHistory, CountsOnlyTheHandsOwnMotion) {
  const HandModel model = build_hand_model(HandDef{});
  int tip = -1;  // a particle riding the index's distal bone
  for (int p = 0; p < model.particle_count() && tip < 0; ++p) {
    int k = 0;
    model.particle_weights.col(p).maxCoeff(&k);
    if (model.particle_bones(k, p) == kIndexDistal) tip = p;
  }
  ASSERT_GE(tip, 0);
  const int palm = [&] {
    for (int p = 0; p < model.particle_count(); ++p)
      if (rigid_part(model, p) == kPalm) return p;
    return -1;
  }();
  ASSERT_GE(palm, 0);
  auto frame = [&](double curl, const Pose& at) {
    HandPoseParams params;
    params.curl = {0, curl, 0, 0, 0};
    return make_hand_frame(Handedness::Right, at, params);
  };
  // Curling with the palm still: the tip moved by `moved`; a face whose inward direction is that motion gets it all.
  Vec3 moved;
  {
    ArticulationHistory history;
    HandState state;
    for (int i = 0; i <= 10; ++i) {
      pose_hand(model, frame(0.06 * i, Pose{}), state);
      history.push(state.bones, 0.03 * i, 0.5);
    }
    const Vec3 x = state.tracked_positions.col(tip);
    pose_hand(model, frame(0.0, Pose{}), state);
    moved = x - Vec3(state.tracked_positions.col(tip));
    ASSERT_GT(moved.norm(), 0.02);
    // The particle is taken to ride its main bone (skinning blends up to four): within 5 % of its skinned motion.
    EXPECT_NEAR(history.inward(model, tip, x, -moved.normalized()), moved.norm(), 0.05 * moved.norm());
    EXPECT_EQ(history.inward(model, tip, x, moved.normalized()), 0.0);  // moving out of that face: nothing
  }
  // The open hand moved 10 cm and turned 60 degrees as a whole: nothing, whatever the face.
  const Pose far{Vec3(0.1, -0.05, 0.02), Quat(Eigen::AngleAxisd(1.0, Vec3(0.3, 1, 0).normalized()))};
  for (const Vec3& n : {Vec3(Vec3::UnitX()), Vec3(Vec3::UnitY()), Vec3(Vec3::UnitZ()), Vec3(Vec3(-1, -1, -1).normalized())}) {
    ArticulationHistory history;
    HandState state;
    for (int i = 0; i <= 10; ++i) {
      const double s = i / 10.0;
      pose_hand(model, frame(0.3, Pose{s * far.position, Quat::Identity().slerp(s, far.orientation)}), state);
      history.push(state.bones, 0.03 * i, 0.5);
    }
    EXPECT_NEAR(history.inward(model, tip, state.tracked_positions.col(tip), n), 0.0, 1e-9);
    EXPECT_NEAR(history.inward(model, palm, state.tracked_positions.col(palm), n), 0.0, 1e-9);
  }
  ArticulationHistory history;
  EXPECT_EQ(history.inward(model, tip, Vec3::Zero(), Vec3::UnitX()), 0.0);  // no samples
  HandState state;
  pose_hand(model, frame(0, Pose{}), state);
  history.push(state.bones, 1.0, 0.5);
  EXPECT_THROW(history.push(state.bones, 1.0, 0.5), Error);  // time must increase
}

// touching_terms and GripHistory::closed_by(terms) (the closing that begins a grasp: the touching digits'): a thumb
// closing towards the index (opposition 0 -> 1, the fingers still, as a clapping hand's thumb does) closes the
// span's thumb term by what the whole span closes, and the little finger's term by nothing; a contact on a finger's
// phalanx names that finger's term (the index's also the thumb's), on the palm none.
TEST(GripHistory, ClosedByTheTouchingDigitsOnly) {
  const HandModel model = build_hand_model(HandDef{});
  auto on_bone = [&](int bone) {
    for (int p = 0; p < model.particle_count(); ++p)
      if (rigid_part(model, p) == bone) return std::vector<ParticleContact>{ParticleContact{p}};
    ADD_FAILURE() << "no particle on bone " << bone;
    return std::vector<ParticleContact>{};
  };
  const unsigned thumb = 1u << kThumbTerm, index = 1u << (kThumbTerm + 1), little = 1u << (kThumbTerm + 4);
  EXPECT_EQ(touching_terms(model, on_bone(kThumbDistal)), thumb);
  EXPECT_EQ(touching_terms(model, on_bone(kIndexIntermediate)), thumb | index);
  EXPECT_EQ(touching_terms(model, on_bone(kLittleProximal)), little);
  EXPECT_EQ(touching_terms(model, on_bone(kPalm)), 0u);
  EXPECT_EQ(touching_terms(model, {}), 0u);

  GripHistory history;
  HandState state;
  for (int i = 0; i <= 10; ++i) {
    HandPoseParams params;
    params.thumb_opposition = 0.1 * i;
    pose_hand(model, make_hand_frame(Handedness::Right, Pose{}, params), state);
    history.push(grip_terms(model, state.bones, 0), Vec3::Zero(), 0.03 * i, 0.5);
    EXPECT_EQ(history.span(), grip_span(model, state.bones, 0));  // the same sum, bit for bit
  }
  ASSERT_GT(history.closed_by(), 0.015);  // the whole hand counts as closing (GraspSettings::closing_distance)
  EXPECT_NEAR(history.closed_by(thumb), history.closed_by(), 1e-12);
  EXPECT_NEAR(history.closed_by(little), 0.0, 1e-12);
  EXPECT_EQ(history.closed_by(0u), 0.0);
  EXPECT_EQ(GripHistory{}.closed_by(thumb), 0.0);  // no samples
}

// ArticulationHistory::point_velocity (PushModel::Wrap's press): a particle's own velocity on its bone. The hand moved
// as a whole at constant velocity gives every particle that velocity; the index curling with the palm still gives
// its tip the speed of its skinned motion (within 5 %: it is taken to ride its main bone) and a palm particle none.
TEST(ArticulationHistory, PointVelocityIsTheParticlesOwn) {
  const HandModel model = build_hand_model(HandDef{});
  int tip = -1, palm = -1;
  for (int p = 0; p < model.particle_count(); ++p) {
    int k = 0;
    model.particle_weights.col(p).maxCoeff(&k);
    if (tip < 0 && model.particle_bones(k, p) == kIndexDistal) tip = p;
    if (palm < 0 && rigid_part(model, p) == kPalm) palm = p;
  }
  ASSERT_GE(tip, 0);
  ASSERT_GE(palm, 0);
  auto frame = [&](double curl, const Vec3& at) {
    HandPoseParams params;
    params.curl = {0, curl, 0, 0, 0};
    return make_hand_frame(Handedness::Right, Pose{at, Quat::Identity()}, params);
  };
  const double dt = 1 / 60.0, span = GraspSettings{}.velocity_window_s;
  const int most = GraspSettings{}.velocity_window;
  {
    const Vec3 u(0.3, -0.1, 0.2);
    ArticulationHistory history;
    HandState state;
    for (int i = 0; i <= 10; ++i) {
      pose_hand(model, frame(0.4, u * (dt * i)), state);
      history.push(state.bones, dt * i, 0.5);
    }
    for (int p : {tip, palm})
      EXPECT_LT((history.point_velocity(model, p, state.tracked_positions.col(p), span, most) - u).norm(), 1e-9);
  }
  ArticulationHistory history;
  HandState state;
  EXPECT_EQ(history.point_velocity(model, tip, Vec3::Zero(), span, most), Vec3::Zero());  // no samples
  Vec3 before = Vec3::Zero();
  for (int i = 0; i <= 10; ++i) {
    if (i > 0) before = state.tracked_positions.col(tip);
    pose_hand(model, frame(0.02 * i, Vec3::Zero()), state);
    history.push(state.bones, dt * i, 0.5);
  }
  const Vec3 skinned = (Vec3(state.tracked_positions.col(tip)) - before) / dt;
  ASSERT_GT(skinned.norm(), 0.05);
  const Vec3 v = history.point_velocity(model, tip, state.tracked_positions.col(tip), span, most);
  EXPECT_LT((v - skinned).norm(), 0.05 * skinned.norm());
  EXPECT_LT(history.point_velocity(model, palm, state.tracked_positions.col(palm), span, most).norm(), 1e-9);
}

TEST(OpposingContacts, FewerThanTwoOrIdenticalNeverOppose) {
  EXPECT_FALSE(opposing_contacts({}));
  EXPECT_FALSE(opposing_contacts({Vec3::UnitX()}));
  EXPECT_FALSE(opposing_contacts({Vec3::UnitX()}, 5.0));
  EXPECT_FALSE(opposing_contacts(std::vector<Vec3>(100, Vec3::UnitZ()), kPaperLiteralCos));
  EXPECT_TRUE(opposing_contacts({Vec3::UnitX(), Vec3::UnitX()}, 5.0));  // c > 1: any pair
}

TEST(OpposingContacts, MatchesBruteForceOnRandomSets) {
  std::mt19937_64 gen(7);
  std::uniform_real_distribution<double> u(0, 1);
  int agree = 0, positives = 0, across_positives = 0;
  for (int trial = 0; trial < 3000; ++trial) {
    int n = 2 + int(u(gen) * 40);
    std::vector<Vec3> d;
    switch (trial % 3) {
      case 0:  // anywhere on the sphere
        for (int i = 0; i < n; ++i) d.push_back(random_unit(gen));
        break;
      case 1:  // a cone around the limit angle of the threshold
        d = cone(gen, random_unit(gen), u(gen) * 1.6, n);
        break;
      default: {  // an arc of a great circle, slightly fuzzed: little for the pruning to work with
        double span = u(gen) * M_PI * 1.1, fuzz = 0.05;
        for (int i = 0; i < n; ++i) {
          double lon = span * u(gen), lat = fuzz * (u(gen) - 0.5);
          d.push_back(Vec3(std::cos(lat) * std::cos(lon), std::cos(lat) * std::sin(lon), std::sin(lat)));
        }
      }
    }
    // three parts, so that many opposing pairs lie within one part
    std::vector<int> parts;
    for (int i = 0; i < n; ++i) parts.push_back(int(u(gen) * 3));
    for (double c : {-0.99, -0.7, 0.0, 0.7, 0.95}) {
      bool expected = brute_force(d, c);
      positives += expected;
      agree += opposing_contacts(d, c) == expected;
      ASSERT_EQ(opposing_contacts(d, c), expected) << "trial " << trial << " c " << c;
      // The pair it names (the world keeps it as the witness of a held grasp) is one that opposes.
      OpposingPair pair{0, 0};
      if (opposing_contacts(d, c, &pair)) {
        ASSERT_NE(pair.first, pair.second) << "trial " << trial;
        ASSERT_LT(d[pair.first].dot(d[pair.second]), c) << "trial " << trial << " c " << c;
      }
      const bool across = brute_force(d, c, &parts);
      across_positives += across;
      ASSERT_EQ(opposing_across_parts(d, parts, c), across) << "trial " << trial << " c " << c << " (parts)";
    }
  }
  EXPECT_EQ(agree, 15000);
  EXPECT_GT(positives - across_positives, 100);  // the parts did exclude pairs
  EXPECT_GT(positives, 1000);
  EXPECT_LT(positives, 14000);
}

TEST(OpposingContacts, BoundaryPairsAreExact) {
  // Pairs whose dot is a hair either side of c.
  for (double c : {-0.7, 0.7}) {
    double angle = std::acos(c);
    for (double eps : {-1e-9, 1e-9}) {
      Vec3 a = Vec3::UnitX();
      Vec3 b(std::cos(angle + eps), std::sin(angle + eps), 0);
      std::vector<Vec3> d{a, b};
      EXPECT_EQ(opposing_contacts(d, c), brute_force(d, c)) << c << " " << eps;
    }
  }
}

TEST(OpposingContacts, ThousandsOfContactsAreFast) {
  std::mt19937_64 gen(3);
  std::vector<Vec3> push = cone(gen, Vec3(0, 1, 0), 1.0, 5000);  // one palm pushing: no grasp
  std::vector<Vec3> grab = cone(gen, Vec3(0, 1, 0), 0.5, 2500);  // plus fingers from the other side
  for (const Vec3& v : cone(gen, Vec3(0, -1, 0), 0.5, 2500)) grab.push_back(v);
  auto t0 = std::chrono::steady_clock::now();
  for (int k = 0; k < 20; ++k) {
    EXPECT_FALSE(opposing_contacts(push));
    EXPECT_TRUE(opposing_contacts(grab));
  }
  double ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
  // All-pairs would be 40 x 12.5M dot products (~0.5 s even optimised); the O(n) paths take ~20 ms.
  EXPECT_LT(ms, 200.0);
}

TEST(OpposingContacts, RejectsNonUnitDirections) {
  EXPECT_THROW(opposing_contacts({Vec3::UnitX(), Vec3(2, 0, 0)}), Error);
  EXPECT_THROW(opposing_contacts({Vec3::UnitX(), Vec3(NAN, 0, 0)}), Error);
  EXPECT_THROW(opposing_contacts({Vec3::UnitX(), Vec3::UnitY()}, NAN), Error);
}

// ---------------------------------------------------------------------------------------------------------
// GraspTracker

TEST(GraspTracker, GraspsAfterKConsecutiveFrames) {
  GraspTracker t;  // k = 2
  EXPECT_EQ(t.update(frame(true, 4)).type, GraspEventType::None);
  EXPECT_FALSE(t.grasped());
  GraspEvent e = t.update(frame(true, 4));
  EXPECT_EQ(e.type, GraspEventType::GraspBegin);
  EXPECT_TRUE(t.grasped());
  EXPECT_EQ(t.update(frame(true, 4)).type, GraspEventType::None);  // one begin only
}

TEST(GraspTracker, DitheringConditionNeverGrasps) {
  GraspTracker t;
  for (int i = 0; i < 200; ++i) {
    EXPECT_EQ(t.update(frame(i % 2 == 0, 3)).type, GraspEventType::None) << i;
    EXPECT_FALSE(t.grasped());
  }
  // Nor does opposition seen by an untracked hand, or "opposing" with a single contact.
  for (int i = 0; i < 10; ++i) t.update(frame(true, 3, false));
  for (int i = 0; i < 10; ++i) t.update(frame(true, 1));
  EXPECT_FALSE(t.grasped());
}

TEST(GraspTracker, ReleaseNeedsOppositionGoneForMFrames) {
  GraspTracker t;  // m = 3
  t.update(frame(true, 4));
  t.update(frame(true, 4));
  ASSERT_TRUE(t.grasped());
  // Single frames and pairs of frames without opposition (or without contacts) do not release.
  for (int i = 0; i < 30; ++i) {
    EXPECT_EQ(t.update(frame(i % 3 == 2, i % 3 == 2 ? 2 : i % 2)).type, GraspEventType::None) << i;
    EXPECT_TRUE(t.grasped());
  }
  // "Opposing" with a single contact is no hold either.
  EXPECT_EQ(t.update(frame(true, 1)).type, GraspEventType::None);
  EXPECT_EQ(t.update(frame(false, 0)).type, GraspEventType::None);
  GraspEvent e = t.update(frame(false, 3));  // the thumb opened, the index still touches: released
  EXPECT_EQ(e.type, GraspEventType::GraspEnd);
  EXPECT_EQ(e.reason, ReleaseReason::Released);
  EXPECT_FALSE(e.zero_velocity);
  EXPECT_FALSE(t.grasped());
  // A new grasp needs a fresh streak.
  EXPECT_EQ(t.update(frame(true, 4)).type, GraspEventType::None);
  EXPECT_EQ(t.update(frame(true, 4)).type, GraspEventType::GraspBegin);
}

TEST(GraspTracker, ShortTrackingLossKeepsGrasp) {
  GraspTracker t;
  t.update(frame(true, 4));
  t.update(frame(true, 4));
  for (int i = 0; i < 5; ++i) {
    EXPECT_EQ(t.update(frame(false, 0, false)).type, GraspEventType::None);  // stale 0 contacts ignored
    EXPECT_TRUE(t.grasped());
  }
  EXPECT_NEAR(t.untracked_time(), 5.0 / 60, 1e-12);
  t.update(frame(true, 3, true));
  EXPECT_TRUE(t.grasped());
  EXPECT_EQ(t.untracked_time(), 0.0);
  // Repeated short losses do not add up.
  for (int r = 0; r < 10; ++r) {
    for (int i = 0; i < 10; ++i) t.update(frame(false, 0, false));
    t.update(frame(true, 3, true));
  }
  EXPECT_TRUE(t.grasped());
}

TEST(GraspTracker, LongTrackingLossReleasesWithZeroVelocity) {
  GraspTracker t;
  t.update(frame(true, 4));
  t.update(frame(true, 4));
  int released_at = -1;
  GraspEvent end;
  for (int i = 0; i < 60; ++i) {
    GraspEvent e = t.update(frame(true, 4, false));
    if (e.type == GraspEventType::GraspEnd) released_at = i, end = e;
  }
  EXPECT_FALSE(t.grasped());
  EXPECT_EQ(end.reason, ReleaseReason::TrackingLost);
  EXPECT_TRUE(end.zero_velocity);
  // Released on the first frame beyond the 0.2 s grace: frame 13 of 60 Hz (0.2167 s).
  EXPECT_EQ(released_at, 12);
}

TEST(GraspTracker, RejectsBadInputAndSettings) {
  GraspTracker t;
  EXPECT_THROW(t.update(frame(true, 2, true, 0.0)), Error);
  EXPECT_THROW(t.update(frame(true, -1)), Error);
  GraspSettings s;
  s.grasp_time_s = -1;
  EXPECT_THROW(GraspTracker{s}, Error);
  s = {};
  s.tracking_grace_s = -1;
  EXPECT_THROW(GraspTracker{s}, Error);
  s = {};
  s.velocity_window = 1;
  EXPECT_THROW(validate_grasp_settings(s), Error);
  for (double bad : {-0.01, 1.5, double(NAN)}) {
    s = {};
    s.velocity_window_s = bad;
    try {
      validate_grasp_settings(s, "world.grasp.");
      ADD_FAILURE() << "velocity_window_s " << bad << " accepted";
    } catch (const Error& e) {
      EXPECT_NE(std::string(e.what()).find("world.grasp.velocity_window_s"), std::string::npos) << e.what();
    }
  }
}

// The hysteresis is in seconds: the same 0.03 s of opposing contacts takes 1 frame at 30 Hz, 2 at 60 Hz and
// 4 at 120 Hz (issue 20: the decision must not depend on the tracker's rate).
TEST(GraspTracker, HysteresisIsInSecondsNotFrames) {
  for (auto [hz, frames] : {std::pair{30.0, 1}, std::pair{60.0, 2}, std::pair{120.0, 4}}) {
    GraspTracker t;
    int begun = -1;
    for (int i = 0; i < 10 && begun < 0; ++i)
      if (t.update(frame(true, 4, true, 1 / hz)).type == GraspEventType::GraspBegin) begun = i + 1;
    EXPECT_EQ(begun, frames) << hz << " Hz";
  }
}

// closing_distance: opposing contacts of a hand that is not closing never begin a grasp; the same contacts
// while it closes do. opening_distance: a held body is let go once the span opens that far over its tightest
// since the grasp began, though the contacts still oppose.
TEST(GraspTracker, ClosingBeginsAndOpeningEnds) {
  GraspSettings s;
  s.closing_distance = 0.015;
  s.opening_distance = 0.025;
  GraspTracker t(s);
  GraspInput still = frame(true, 8);
  still.closing = false;
  still.span = 0.5;
  for (int i = 0; i < 60; ++i) EXPECT_EQ(t.update(still).type, GraspEventType::None);
  GraspInput closing = still;
  closing.closing = true;
  EXPECT_EQ(t.update(closing).type, GraspEventType::None);
  EXPECT_EQ(t.update(closing).type, GraspEventType::GraspBegin);
  GraspInput held = still;  // still closing no more: a held body needs no closing
  for (double span : {0.5, 0.45, 0.40, 0.42, 0.424}) {
    held.span = span;
    EXPECT_EQ(t.update(held).type, GraspEventType::None) << span;  // tightest 0.40, opened 2.4 cm at most
  }
  held.span = 0.426;  // 2.6 cm over the tightest: open for release_time_s (3 frames at 60 Hz)
  EXPECT_EQ(t.update(held).type, GraspEventType::None);
  EXPECT_EQ(t.update(held).type, GraspEventType::None);
  const GraspEvent e = t.update(held);
  EXPECT_EQ(e.type, GraspEventType::GraspEnd);
  EXPECT_EQ(e.reason, ReleaseReason::Released);
}

// A held pair's closing is not read (decide_grasps's closes_on skips the window's scan while the pair holds): a
// grasped tracker fed the same frames with closing true and false answers alike, frame by frame, to the release.
TEST(GraspTracker, HeldReadsNoClosing) {
  GraspSettings s;
  s.closing_distance = 0.015;
  s.opening_distance = 0.025;
  std::mt19937 rng(25);
  for (int trial = 0; trial < 200; ++trial) {
    GraspTracker with(s);
    GraspInput begin = frame(true, 8);
    while (!with.grasped()) with.update(begin);
    GraspTracker without = with;
    for (int i = 0; i < 200 && with.grasped(); ++i) {
      GraspInput in = frame(rng() % 8 != 0, int(rng() % 4));
      in.hand_tracked = rng() % 16 != 0;
      in.span = 0.4 + 0.001 * double(rng() % 40);
      in.closing = true;
      const GraspEvent a = with.update(in);
      in.closing = false;
      const GraspEvent b = without.update(in);
      ASSERT_EQ(a.type, b.type) << trial << " " << i;
      ASSERT_EQ(a.reason, b.reason);
      ASSERT_EQ(a.zero_velocity, b.zero_velocity);
      ASSERT_EQ(with.grasped(), without.grasped());
      ASSERT_EQ(with.untracked_time(), without.untracked_time());
    }
  }
}

// GripHistory: how much the span shrank within the window, and how far two hands' palms approached.
TEST(GripHistory, ClosedByAndApproachedByWithinTheWindow) {
  GripHistory a, b;
  EXPECT_EQ(a.closed_by(), 0.0);
  for (int i = 0; i <= 60; ++i) {
    const double t = i / 60.0;
    a.push({0.6 - 0.1 * std::max(t - 0.5, 0.0)}, Vec3(0.2 - 0.1 * t, 0, 0), t, 0.5);  // closes 5 cm in the last 0.5 s
    b.push({0.6}, Vec3(-0.2, 0, 0), t, 0.5);
  }
  EXPECT_NEAR(a.closed_by(), 0.05, 1e-12);  // widest in the window (t = 0.5 s) 0.6, now 0.55
  EXPECT_NEAR(a.span(), 0.55, 1e-12);
  EXPECT_NEAR(a.approached_by(b), 0.05, 1e-9);  // palms 0.35 m apart at t = 0.5 s, 0.3 m at t = 1 s
  EXPECT_EQ(b.closed_by(), 0.0);
  EXPECT_THROW(a.push({0.5}, Vec3::Zero(), 0.5, 0.5), Error);  // time must increase
  EXPECT_THROW(a.push({NAN}, Vec3::Zero(), 2.0, 0.5), Error);
}

// ---------------------------------------------------------------------------------------------------------
// HandMotionHistory

namespace {

// Constant linear velocity of the palm and constant world-frame angular velocity of its orientation.
struct ConstantMotion {
  Vec3 p0{0.1, 1.2, -0.3}, v{0.8, -0.3, 1.5}, w{2.0, -1.0, 3.5};
  Quat q0 = Quat(Eigen::AngleAxisd(0.7, Vec3(1, 1, 0).normalized()));
  Pose at(double t) const {
    Quat q = Quat(Eigen::AngleAxisd(w.norm() * t, w.normalized())) * q0;
    return {p0 + v * t, q};
  }
};

}  // namespace

TEST(HandMotionHistory, RecoversConstantMotionExactly) {
  ConstantMotion m;
  HandMotionHistory h(4);
  double t0 = 1000.0, dt = 1.0 / 60;
  for (int k = 0; k < 10; ++k) h.push(m.at(k * dt), t0 + k * dt);
  EXPECT_EQ(h.size(), 4);
  EXPECT_LE((h.linear_velocity() - m.v).norm(), 1e-9);
  EXPECT_LE((h.angular_velocity() - m.w).norm(), 1e-9);
  // A point attached to the palm: x(t) = p(t) + R(t) r. Its derivative at the newest sample, by a central
  // difference of the true trajectory, is what the released object should get.
  double tn = 9 * dt;
  Vec3 r_local(0.05, -0.02, 0.1);
  Vec3 x = m.at(tn).transform(r_local);
  double h_fd = 1e-6;
  Vec3 v_true = (m.at(tn + h_fd).transform(r_local) - m.at(tn - h_fd).transform(r_local)) / (2 * h_fd);
  EXPECT_LE((h.point_velocity(x) - v_true).norm(), 1e-7);  // limited by the finite difference
  EXPECT_LE((h.point_velocity(x) - (m.v + m.w.cross(x - m.at(tn).position))).norm(), 1e-9);
  BodyVelocity b = h.attached_body_velocity(x);
  EXPECT_EQ(b.linear, h.point_velocity(x));
  EXPECT_EQ(b.angular, h.angular_velocity());
}

TEST(HandMotionHistory, IrregularTimestampsStillExact) {
  ConstantMotion m;
  HandMotionHistory h(5);
  double t = 0;
  for (double dt : {0.016, 0.017, 0.011, 0.033, 0.016, 0.02}) {
    t += dt;
    h.push(m.at(t), t);
  }
  EXPECT_LE((h.linear_velocity() - m.v).norm(), 1e-9);
  EXPECT_LE((h.angular_velocity() - m.w).norm(), 1e-9);
}

TEST(HandMotionHistory, SingleJitteryFrameHurtsLessThanFiniteDifference) {
  ConstantMotion m;
  m.w.setZero();
  double dt = 1.0 / 60;
  Vec3 jitter(0.005, 0, 0);  // 5 mm tracking glitch on the newest frame
  HandMotionHistory h(4), two(2);
  for (int k = 0; k < 4; ++k) {
    Pose p = m.at(k * dt);
    if (k == 3) p.position += jitter;
    h.push(p, k * dt);
    two.push(p, k * dt);
  }
  double err_lsq = (h.linear_velocity() - m.v).norm(), err_fd = (two.linear_velocity() - m.v).norm();
  EXPECT_NEAR(err_fd, jitter.norm() / dt, 1e-9);
  EXPECT_NEAR(err_lsq, 0.3 * jitter.norm() / dt, 1e-9);  // 1.5 dt / (5 dt^2) of the glitch
}

// The velocity's window is GraspSettings::velocity_window_s (0.05 s), whole frames back to the first sample that
// old: 3 samples at 30 Hz, 4 at 45 and 60 Hz, 7 at 120 Hz (not 4 at every rate: 100 ms at 30 Hz, 25 ms at 120).
// Under a constant acceleration a least-squares slope over equally spaced samples is the velocity at their mean
// time, so it lags the newest sample by half the window.
TEST(HandMotionHistory, WindowIsInSecondsNotFrames) {
  const double accel = 2.0;
  for (auto [hz, samples] : {std::pair{30.0, 3}, std::pair{45.0, 4}, std::pair{60.0, 4}, std::pair{120.0, 7}}) {
    HandMotionHistory h;
    const int frames = int(std::lround(hz));  // 1 s
    for (int i = 0; i <= frames; ++i) {
      const double t = i / hz;
      h.push(Pose{Vec3(0.5 * accel * t * t, 0, 0), Quat::Identity()}, t);
    }
    const double lag = (samples - 1) / hz / 2;
    EXPECT_NEAR(h.linear_velocity().x(), accel * (1.0 - lag), 1e-9) << hz << " Hz";
    HandMotionHistory frames4(4, 0.0);  // the rule before: the last 4 frames at any rate
    for (int i = 0; i <= frames; ++i) {
      const double t = i / hz;
      frames4.push(Pose{Vec3(0.5 * accel * t * t, 0, 0), Quat::Identity()}, t);
    }
    EXPECT_NEAR(frames4.linear_velocity().x(), accel * (1.0 - 1.5 / hz), 1e-9) << hz << " Hz";
  }
}

TEST(HandMotionHistory, TooFewSamplesGiveZeroAndBadInputThrows) {
  HandMotionHistory h;
  EXPECT_EQ(h.window(), 16);
  EXPECT_EQ(h.linear_velocity(), Vec3::Zero());
  h.push(Pose{}, 0.0);
  EXPECT_FALSE(h.has_velocity());
  EXPECT_EQ(h.angular_velocity(), Vec3::Zero());
  EXPECT_EQ(h.point_velocity(Vec3(1, 2, 3)), Vec3::Zero());
  EXPECT_THROW(h.push(Pose{}, 0.0), Error);  // time must increase
  EXPECT_THROW(h.push(Pose{Vec3(NAN, 0, 0), Quat::Identity()}, 1.0), Error);
  EXPECT_THROW(HandMotionHistory(1), Error);
  EXPECT_THROW(HandMotionHistory(4, -0.01), Error);
  EXPECT_EQ(h.size(), 1);
  h.clear();
  EXPECT_EQ(h.size(), 0);
}

namespace {

// capsule_gap by brute force: the segments sampled finely, then refined around the best sample pair.
double brute_capsule_gap(const Vec3& a0, const Vec3& a1, double ra0, double ra1, const Vec3& b0, const Vec3& b1,
                         double rb0, double rb1) {
  auto gap = [&](double s, double t) {
    return (a0 + s * (a1 - a0) - b0 - t * (b1 - b0)).norm() - (ra0 + s * (ra1 - ra0)) - (rb0 + t * (rb1 - rb0));
  };
  double best = gap(0, 0), bs = 0, bt = 0, step = 1.0 / 200;
  for (int i = 0; i <= 200; ++i)
    for (int j = 0; j <= 200; ++j)
      if (const double g = gap(i * step, j * step); g < best) best = g, bs = i * step, bt = j * step;
  for (int round = 0; round < 40; ++round, step *= 0.5)
    for (int i = -2; i <= 2; ++i)
      for (int j = -2; j <= 2; ++j) {
        const double s = std::clamp(bs + i * step, 0.0, 1.0), t = std::clamp(bt + j * step, 0.0, 1.0);
        if (const double g = gap(s, t); g < best) best = g, bs = s, bt = t;
      }
  return best;
}

}  // namespace

// capsule_gap: the pads' surfaces. Closed-form cases, then random segments (crossing, parallel, points, tapered
// radii) against a brute-force search.
TEST(CapsuleGap, MatchesClosedFormAndBruteForce) {
  // Two parallel unit capsules 5 cm apart, side by side and offset along their axis.
  EXPECT_NEAR(capsule_gap(Vec3(0, 0, 0), Vec3(0.02, 0, 0), 0.01, 0.01, Vec3(0, 0.05, 0), Vec3(0.02, 0.05, 0), 0.01, 0.01),
              0.03, 1e-15);
  EXPECT_NEAR(capsule_gap(Vec3(0, 0, 0), Vec3(0.02, 0, 0), 0.01, 0.01, Vec3(0.03, 0.04, 0), Vec3(0.05, 0.04, 0), 0.01,
                          0.01),
              std::hypot(0.01, 0.04) - 0.02, 1e-15);
  // Crossing at right angles, 2 cm apart: the radii where they cross (tapered: half way along each).
  EXPECT_NEAR(capsule_gap(Vec3(-0.01, 0, 0), Vec3(0.01, 0, 0), 0.004, 0.008, Vec3(0, -0.01, 0.02), Vec3(0, 0.01, 0.02),
                          0.002, 0.006),
              0.02 - 0.006 - 0.004, 1e-15);
  // Two points, and overlapping capsules (negative).
  EXPECT_NEAR(capsule_gap(Vec3::Zero(), Vec3::Zero(), 0.01, 0.01, Vec3(0.01, 0, 0), Vec3(0.01, 0, 0), 0.005, 0.005),
              -0.005, 1e-15);
  std::mt19937_64 gen(7);
  std::uniform_real_distribution<double> x(-0.03, 0.03), r(0.006, 0.01), taper(-0.001, 0.001), pick(0, 1);
  double worst = 0;
  for (int k = 0; k < 400; ++k) {
    Vec3 a0(x(gen), x(gen), x(gen)), a1(x(gen), x(gen), x(gen)), b0(x(gen), x(gen), x(gen)), b1;
    const double kind = pick(gen);
    if (kind < 0.2) b1 = b0 + (a1 - a0) * 0.7;  // parallel
    else if (kind < 0.3) b1 = b0;               // a point
    else b1 = Vec3(x(gen), x(gen), x(gen));
    if (k % 7 == 0) a1 = a0;
    const bool tapered = k % 2;
    const double ra0 = r(gen), rb0 = r(gen);
    const double ra1 = tapered ? ra0 + taper(gen) : ra0, rb1 = tapered ? rb0 + taper(gen) : rb0;
    const double got = capsule_gap(a0, a1, ra0, ra1, b0, b1, rb0, rb1);
    const double want = brute_capsule_gap(a0, a1, ra0, ra1, b0, b1, rb0, rb1);
    EXPECT_GE(got, want - 1e-12) << k;  // the gap at some pair of points: never below the least
    if (!tapered) EXPECT_NEAR(got, want, 1e-12) << k;
    // With a taper the gap is taken at the axes' closest points, and the surfaces' lie elsewhere (for nearly parallel
    // bones anywhere along them): it exceeds the least gap by at most how much the radii change along the bones.
    const double bound = std::abs(ra1 - ra0) + std::abs(rb1 - rb0);
    EXPECT_LE(got - want, bound + 1e-12) << k;
    worst = std::max(worst, (got - want) / std::max(bound, 1e-12));
  }
  std::printf("capsule_gap over the least gap, tapered: at most %.2f of the radii's change\n", worst);
}

// grip_terms from a GripBind made once (a hand slot's) against the terms as they were computed before it: each joint
// at bones[j] times the inverse of bind_inverse[j] made on the spot; the same bits, for both hands, random poses and
// pinch reaches 0 (the tips' distance) and > 0 (the pads' capsule gap).
TEST(GripSpan, BindMadeOnceGivesTheSameTerms) {
  std::mt19937 rng(25);
  std::uniform_real_distribution<double> unit(0, 1);
  for (Handedness side : {Handedness::Right, Handedness::Left}) {
    HandDef def;
    def.handedness = side;
    const HandModel model = build_hand_model(def);
    const GripBind bind = grip_bind(model);
    for (int k = 0; k < 200; ++k) {
      HandPoseParams params;
      for (double& c : params.curl) c = unit(rng);
      params.thumb_opposition = unit(rng);
      params.spread = unit(rng) - 0.2;
      const Pose at{Vec3(unit(rng), unit(rng), unit(rng)),
                    Quat(Eigen::AngleAxisd(6 * unit(rng), Vec3(unit(rng) - 0.5, 1, unit(rng)).normalized()))};
      HandState state;
      pose_hand(model, make_hand_frame(side, at, params), state);
      auto joint = [&](int j) { return Vec3(state.bones[j] * model.bind_inverse[j].inverse().position.homogeneous()); };
      auto r = [&](int j) { return model.bind.joints[j].radius; };
      for (double reach : {0.0, 0.04}) {
        GripTerms want;
        want[kThumbTerm] = reach > 0 ? std::min(reach, capsule_gap(joint(kThumbDistal), joint(kThumbTip), r(kThumbDistal),
                                                                   r(kThumbTip), joint(kIndexDistal), joint(kIndexTip),
                                                                   r(kIndexDistal), r(kIndexTip)))
                                     : (joint(kThumbTip) - joint(kIndexTip)).norm();
        int term = kThumbTerm + 1;
        for (int tip : {kIndexTip, kMiddleTip, kRingTip, kLittleTip}) want[term++] = (joint(tip) - joint(kPalm)).norm();
        const GripTerms got = grip_terms(bind, state.bones, reach);
        for (size_t i = 0; i < want.size(); ++i) EXPECT_EQ(got[i], want[i]) << k << " " << reach << " " << i;
      }
    }
  }
}

// grip_span's thumb term (GraspSettings::pinch_reach): 0 is the tip joints' distance in full; > 0 is the thumb and
// index pads' gap (capsule_gap with the model's joint radii), at most the reach. A thumb swinging towards the index
// while its pad is beyond the reach closes the span by nothing; closing within the reach counts as the pads close.
TEST(GripSpan, PinchReachCountsTheThumbOnlyNearTheIndex) {
  const HandModel model = build_hand_model(HandDef{});
  const Pose at{Vec3(0.1, 0.2, -0.3), Quat(Eigen::AngleAxisd(0.7, Vec3(1, 2, 3).normalized()))};
  auto bones = [&](double opposition, double spread, double curl = 0.2) {
    HandPoseParams params;
    params.curl = {0, curl, curl + 0.1, curl + 0.2, curl + 0.3};
    params.thumb_opposition = opposition;
    params.spread = spread;
    HandState state;
    pose_hand(model, make_hand_frame(Handedness::Right, at, params), state);
    return std::make_pair(state.bones, make_hand_frame(Handedness::Right, at, params));
  };
  for (double opposition : {0.0, 0.2, 0.4, 0.7, 1.0})
    for (double spread : {-0.2, 0.0, 0.8}) {
      const auto [b, f] = bones(opposition, spread);
      auto x = [&](int j) { return f.joints[j].position; };
      auto r = [&](int j) { return model.bind.joints[j].radius; };
      double fingers = 0;
      for (int tip : {kIndexTip, kMiddleTip, kRingTip, kLittleTip}) fingers += (x(tip) - x(kPalm)).norm();
      const double pads = capsule_gap(x(kThumbDistal), x(kThumbTip), r(kThumbDistal), r(kThumbTip), x(kIndexDistal),
                                      x(kIndexTip), r(kIndexDistal), r(kIndexTip));
      EXPECT_NEAR(grip_span(model, b, 0), fingers + (x(kThumbTip) - x(kIndexTip)).norm(), 1e-12);
      for (double reach : {0.02, 0.04, 0.065})
        EXPECT_NEAR(grip_span(model, b, reach), fingers + std::min(reach, pads), 1e-12) << opposition << " " << reach;
    }
  // The flat hand's thumb swinging towards the index (opposition 0 -> 0.2: the tips 1 cm nearer, the pads 4.7 cm apart
  // and more) closes nothing with a 4 cm reach; closing on from 0.4 to 1 (pads 3.7 -> 1.5 cm) counts as the pads close.
  auto span = [&](double opposition, double reach) { return grip_span(model, bones(opposition, 0, 0).first, reach); };
  EXPECT_GT(span(0, 0) - span(0.2, 0), 0.009);
  EXPECT_NEAR(span(0, 0.04) - span(0.2, 0.04), 0.0, 1e-12);
  EXPECT_GT(span(0.4, 0.04) - span(1.0, 0.04), 0.02);
}

namespace {
struct TimedSample {
  double time = 0;
  int id = 0;
};
// Hands SampleWindow::visit_state's list over, as save (a copy) and restore (the window's own storage) see it.
struct ListVisitor {
  std::vector<int> ids;
  template <class List, class F> void list(List& samples, F) {
    ids.clear();
    for (const TimedSample& s : samples) ids.push_back(s.id);
  }
};
}  // namespace

// The ring holds what a list that drops its samples older than the window from the front holds, oldest first,
// through windows that shrink and grow (the ring grows and wraps), saves and restores, and pushes of both kinds.
TEST(SampleWindow, HoldsWhatAListDroppingTheOldSamplesHolds) {
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> gap(0.001, 0.03), window(0.0, 0.5);
  SampleWindow<TimedSample> ring;
  std::vector<TimedSample> list;
  double time = 0;
  for (int i = 0; i < 5000; ++i) {
    time += gap(rng);
    const double w = i % 700 < 350 ? window(rng) : 0.5;  // long runs of a full window, then short ones
    if (i % 2) {
      ring.push(TimedSample{time, i}, w);
    } else {
      ring.push_made(time, w, [i](TimedSample& s) { s.id = i; });
    }
    list.push_back({time, i});
    while (list.size() > 1 && list.front().time < time - w - 1e-9) list.erase(list.begin());
    ASSERT_EQ(ring.size(), list.size()) << i;
    std::vector<int> seen;
    ring.for_each([&](const TimedSample& s) { seen.push_back(s.id); });
    for (size_t k = 0; k < list.size(); ++k) {
      ASSERT_EQ(ring[k].id, list[k].id) << i;
      ASSERT_EQ(seen[k], list[k].id) << i;
    }
    ASSERT_EQ(ring.back().id, i);
    if (i % 97 == 0) {
      ListVisitor saved, restored;
      SampleWindow<TimedSample>::visit_state(std::as_const(ring), saved, 0);
      SampleWindow<TimedSample>::visit_state(ring, restored, 0);
      ASSERT_EQ(saved.ids, restored.ids) << i;
      ASSERT_EQ(saved.ids.size(), list.size()) << i;
      for (size_t k = 0; k < list.size(); ++k) ASSERT_EQ(saved.ids[k], list[k].id) << i;
    }
  }
  EXPECT_THROW(ring.push(TimedSample{time, -1}, 0.5), Error) << "times must increase";
  EXPECT_EQ(ring.back().id, 4999) << "a refused push leaves the window as it was";
}
