// Synthetic hand frames: anatomy, mirror symmetry, pinch and fist, frame validation.
#include "handsim/hand.h"
#include "world_impl.h"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <random>

using namespace handsim;

namespace {

Pose some_pose() {
  Pose p;
  p.position = Vec3(0.3, 1.1, -0.4);
  p.orientation = Quat(Eigen::AngleAxisd(0.7, Vec3(1, 2, 3).normalized()));
  return p;
}

const int kTips[5] = {kThumbTip, kIndexTip, kMiddleTip, kRingTip, kLittleTip};

// The joint whose bone ends at joint j (none for palm, wrist and metacarpals).
int parent_joint(int j) {
  if (j <= kWrist || j == kThumbMetacarpal || j == kIndexMetacarpal || j == kMiddleMetacarpal ||
      j == kRingMetacarpal || j == kLittleMetacarpal)
    return -1;
  return j - 1;
}

}  // namespace

TEST(HandFrame, BindFrameIsAnAdultRightHand) {
  HandFrame f = bind_frame(Handedness::Right);
  EXPECT_TRUE(f.tracked());
  for (const JointPose& j : f.joints) {
    EXPECT_TRUE(j.valid);
    EXPECT_NEAR(j.orientation.norm(), 1.0, 1e-12);
    EXPECT_GE(j.radius, 0.007);
    EXPECT_LE(j.radius, 0.0145);
  }
  EXPECT_TRUE(f.joints[kPalm].position.isZero(1e-15));
  // Palm ~9 cm from wrist to the middle knuckle, fingers along -Z, thumb on -X for the right hand.
  EXPECT_NEAR((f.joints[kWrist].position - f.joints[kMiddleProximal].position).norm(), 0.09, 0.005);
  double middle = (f.joints[kMiddleTip].position - f.joints[kMiddleProximal].position).norm();
  EXPECT_NEAR(middle, 0.08, 0.005);
  double width = f.joints[kLittleProximal].position.x() - f.joints[kIndexProximal].position.x() +
                 f.joints[kLittleProximal].radius + f.joints[kIndexProximal].radius;
  EXPECT_NEAR(width, 0.08, 0.006);
  EXPECT_LT(f.joints[kMiddleTip].position.z(), -0.11);
  EXPECT_LT(f.joints[kThumbTip].position.x(), f.joints[kIndexTip].position.x());
}

TEST(HandFrame, OrientationsFollowTheBones) {
  for (Handedness h : {Handedness::Left, Handedness::Right}) {
    HandPoseParams p;
    p.curl = {0.3, 0.6, 0.2, 0.9, 0.5};
    p.thumb_opposition = 0.4;
    p.spread = 0.5;
    HandFrame f = make_hand_frame(h, some_pose(), p);
    for (int j = 0; j < kHandJointCount; ++j) {
      int parent = parent_joint(j);
      if (parent < 0) continue;
      Vec3 bone = (f.joints[j].position - f.joints[parent].position).normalized();
      Vec3 minus_z = f.joints[parent].orientation * -Vec3::UnitZ();
      EXPECT_GT(bone.dot(minus_z), 1 - 1e-9) << "joint " << parent;
    }
    // The back of the hand is the palm's +Y: the palm joint's orientation is the palm pose's.
    EXPECT_TRUE(f.joints[kPalm].orientation.isApprox(some_pose().orientation, 1e-12));
  }
}

TEST(HandFrame, LeftIsTheMirrorOfRight) {
  HandPoseParams p;
  p.curl = {0.5, 0.1, 0.4, 0.7, 1.0};
  p.thumb_opposition = 0.6;
  HandFrame r = make_hand_frame(Handedness::Right, Pose{}, p);
  HandFrame l = make_hand_frame(Handedness::Left, Pose{}, p);
  EXPECT_EQ(l.handedness, Handedness::Left);
  for (int j = 0; j < kHandJointCount; ++j) {
    Vec3 m = r.joints[j].position;
    m.x() = -m.x();
    EXPECT_TRUE(l.joints[j].position.isApprox(m, 1e-12) || (m - l.joints[j].position).norm() < 1e-12);
    // Mirrored bone direction (-Z) and back direction (+Y).
    Vec3 rz = r.joints[j].orientation * Vec3::UnitZ(), lz = l.joints[j].orientation * Vec3::UnitZ();
    Vec3 ry = r.joints[j].orientation * Vec3::UnitY(), ly = l.joints[j].orientation * Vec3::UnitY();
    EXPECT_NEAR((Vec3(-rz.x(), rz.y(), rz.z()) - lz).norm(), 0, 1e-12);
    EXPECT_NEAR((Vec3(-ry.x(), ry.y(), ry.z()) - ly).norm(), 0, 1e-12);
  }
  EXPECT_GT(l.joints[kThumbTip].position.x(), l.joints[kIndexTip].position.x());
}

TEST(HandFrame, PinchBringsThumbTipToIndexTip) {
  for (Handedness h : {Handedness::Left, Handedness::Right}) {
    for (double index_curl : {0.4, 0.5, 0.6}) {
      HandPoseParams p;
      p.curl[1] = index_curl;
      p.thumb_opposition = 1;
      HandFrame f = make_hand_frame(h, some_pose(), p);
      double d = (f.joints[kThumbTip].position - f.joints[kIndexTip].position).norm();
      // Pads touching: the distance is the sum of the tip radii (~1.6 cm).
      EXPECT_LT(d, 0.02) << "index curl " << index_curl;
      EXPECT_NEAR(d, f.joints[kThumbTip].radius + f.joints[kIndexTip].radius, 1e-6);
    }
    // Without opposition the thumb stays far from the curled index.
    HandPoseParams open;
    open.curl[1] = 0.5;
    HandFrame f = make_hand_frame(h, some_pose(), open);
    EXPECT_GT((f.joints[kThumbTip].position - f.joints[kIndexTip].position).norm(), 0.04);
  }
}

TEST(HandFrame, FistClosesFingertipsOntoThePalm) {
  HandPoseParams fist;
  fist.curl = {1, 1, 1, 1, 1};
  HandFrame flat = make_hand_frame(Handedness::Right, Pose{}, {});
  HandFrame f = make_hand_frame(Handedness::Right, Pose{}, fist);
  for (int i = 1; i < 5; ++i) {
    Vec3 tip = f.joints[kTips[i]].position;
    double flat_d = flat.joints[kTips[i]].position.norm();
    EXPECT_GT(flat_d, 0.09);
    EXPECT_LT(tip.norm(), 0.055) << "finger " << i;  // fingertips near the palm centre
    EXPECT_LT(tip.y(), -0.005) << "finger " << i;     // on the palm side
  }
  // The curled thumb moves towards the fingers.
  EXPECT_LT((f.joints[kThumbTip].position - f.joints[kIndexIntermediate].position).norm(),
            (flat.joints[kThumbTip].position - flat.joints[kIndexIntermediate].position).norm());
}

TEST(HandFrame, ScaleScalesEverything) {
  HandFrame a = bind_frame(Handedness::Right, 1.0), b = bind_frame(Handedness::Right, 1.25);
  for (int j = 0; j < kHandJointCount; ++j) {
    EXPECT_NEAR((b.joints[j].position - 1.25 * a.joints[j].position).norm(), 0, 1e-12);
    EXPECT_NEAR(b.joints[j].radius, 1.25 * a.joints[j].radius, 1e-12);
  }
}

TEST(HandFrame, BadParametersThrowNamingTheArgument) {
  HandPoseParams p;
  p.scale = -1;
  try {
    make_hand_frame(Handedness::Right, Pose{}, p);
    FAIL();
  } catch (const Error& e) {
    EXPECT_EQ(e.argument(), "params.scale");
  }
  Pose bad;
  bad.orientation = Quat(0.5, 0, 0, 0);
  try {
    make_hand_frame(Handedness::Right, bad);
    FAIL();
  } catch (const Error& e) {
    EXPECT_EQ(e.argument(), "palm_pose.orientation");
  }
}

TEST(HandFrame, ValidateFrameRejectsBadValidJoints) {
  HandFrame good = make_hand_frame(Handedness::Right, some_pose());
  EXPECT_NO_THROW(validate_frame(good, "frame"));

  auto expect_error = [](const HandFrame& f, const std::string& arg) {
    try {
      validate_frame(f, "frame");
      FAIL() << "expected an error on " << arg;
    } catch (const Error& e) {
      EXPECT_EQ(e.argument(), arg);
      EXPECT_EQ(e.status(), Status::InvalidArgument);
    }
  };
  HandFrame f = good;
  f.joints[7].position.y() = std::nan("");
  expect_error(f, "frame.joints[7].position");
  f = good;
  f.joints[12].orientation.coeffs() *= 1.1;
  expect_error(f, "frame.joints[12].orientation");
  f = good;
  f.joints[3].radius = -0.001;
  expect_error(f, "frame.joints[3].radius");
  f = good;
  f.joints[20].radius = std::nan("");
  expect_error(f, "frame.joints[20].radius");

  // NaN in an invalid joint is legal.
  f = good;
  f.joints[9].valid = false;
  f.joints[9].position = Vec3::Constant(std::nan(""));
  f.joints[9].orientation.coeffs().setConstant(std::nan(""));
  f.joints[9].radius = -5;
  EXPECT_NO_THROW(validate_frame(f, "frame"));
}

// The step's frame check (four joints at a time where the CPU has AVX2) gives the one-joint-at-a-time answer on
// joints at and around every bound: coordinates near +-1e7 m, quaternion norms near 1 +- 1e-3, radii near 0 and
// the largest, NaN and infinities, valid and not.
TEST(HandFrame, TheStepsFrameCheckIsTheScalarOnesAnswer) {
  std::mt19937_64 rng(25);
  std::uniform_real_distribution<double> uniform(-1, 1);
  std::uniform_int_distribution<int> pick(0, 9);
  const double inf = std::numeric_limits<double>::infinity(), nan = std::nan("");
  auto near = [&](double x) {  // x, or a few ulps either side of it
    for (int n = pick(rng) - 5; n != 0; n += n > 0 ? -1 : 1) x = std::nextafter(x, n > 0 ? inf : -inf);
    return x;
  };
  int valid = 0, invalid = 0;
  for (int t = 0; t < 20000; ++t) {
    HandFrame f = make_hand_frame(t % 2 ? Handedness::Left : Handedness::Right, some_pose(), HandPoseParams{});
    const int bad_joints = pick(rng) % 3;
    for (int b = 0; b < bad_joints; ++b) {
      JointPose& jp = f.joints[size_t(pick(rng) * 2 + pick(rng) % 2 + (pick(rng) > 5 ? 6 : 0)) % kHandJointCount];
      switch (pick(rng)) {
        case 0: jp.position[pick(rng) % 3] = near(pick(rng) % 2 ? 1e7 : -1e7); break;
        case 1: jp.orientation.coeffs() *= near(1 + (pick(rng) % 2 ? 1e-3 : -1e-3)); break;
        case 2: jp.radius = near(pick(rng) % 2 ? 0.0 : 1e7); break;
        case 3: jp.position[pick(rng) % 3] = pick(rng) % 2 ? nan : -inf; break;
        case 4: jp.orientation.coeffs()[pick(rng) % 4] = pick(rng) % 2 ? nan : inf; break;
        case 5: jp.radius = nan; break;
        case 6: jp.valid = false; jp.position.x() = nan; break;
        default: jp.orientation.coeffs() *= 1 + 2e-3 * uniform(rng); break;
      }
    }
    const bool scalar = joints_are_good(f);
    ASSERT_EQ(frame_is_valid(f), scalar) << "frame " << t;
    ++(scalar ? valid : invalid);
  }
  EXPECT_GT(valid, 5000);
  EXPECT_GT(invalid, 3000);
}
