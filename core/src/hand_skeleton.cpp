// Synthetic OpenXR hand frames. The hand is built as a right hand in the palm's local frame (palm joint at
// the origin, fingers along -Z, back of the hand +Y, thumb on -X), mirrored for the left hand, then placed at
// the palm pose. Dimensions are those of an adult hand at scale 1.
#include "handsim/hand.h"

#include "simd4.h"
#include "validate.h"

#include <algorithm>
#include <cmath>

namespace handsim {
namespace {

constexpr double kDeg = M_PI / 180.0;

struct FingerSpec {
  int first_joint;               // metacarpal joint index
  Vec3 base;                     // metacarpal joint (carpometacarpal), palm frame, right hand
  Vec3 knuckle;                  // proximal joint (MCP)
  std::array<double, 3> length;  // proximal, intermediate, distal (to the tip joint)
  std::array<double, 5> radius;  // metacarpal, proximal, intermediate, distal, tip
  double spread_deg;             // rotation about +Y at spread 1 (positive: towards the thumb)
};

// Knuckles span 6.4 cm centre to centre, so the palm with its skin is ~8.4 cm wide; the middle finger is
// 4.0 + 2.3 + 1.8 = 8.1 cm from its knuckle to its tip joint.
const FingerSpec kFingers[4] = {
    {kIndexMetacarpal, {-0.012, 0.0, 0.035}, {-0.024, 0.0, -0.043}, {0.036, 0.021, 0.017},
     {0.0110, 0.0100, 0.0090, 0.0082, 0.0078}, 9.0},
    {kMiddleMetacarpal, {-0.002, 0.0, 0.035}, {0.000, 0.0, -0.045}, {0.040, 0.023, 0.018},
     {0.0110, 0.0105, 0.0093, 0.0085, 0.0080}, 0.0},
    {kRingMetacarpal, {0.010, 0.0, 0.035}, {0.021, 0.0, -0.042}, {0.037, 0.023, 0.018},
     {0.0105, 0.0100, 0.0090, 0.0082, 0.0078}, -7.0},
    {kLittleMetacarpal, {0.020, 0.0, 0.033}, {0.040, 0.0, -0.037}, {0.029, 0.017, 0.016},
     {0.0100, 0.0090, 0.0083, 0.0078, 0.0073}, -15.0},
};
// Flexion at curl 1 (MCP, PIP, DIP): a closed fist.
constexpr double kFingerFlexDeg[3] = {90.0, 105.0, 70.0};

// Thumb: carpometacarpal joint near the wrist, slightly on the palm side.
const Vec3 kThumbBase(-0.022, -0.008, 0.030);
const Vec3 kThumbDir(-0.55, -0.12, -0.83);   // metacarpal direction of the relaxed flat thumb
const Vec3 kThumbNail(-0.7, 0.7, 0.0);       // the thumb nail faces outwards and up
constexpr double kThumbLength[3] = {0.044, 0.032, 0.026};  // metacarpal, proximal, distal
constexpr double kThumbRadius[4] = {0.0125, 0.0105, 0.0095, 0.0085};
constexpr double kThumbFlexDeg[3] = {20.0, 55.0, 75.0};   // CMC, MCP, IP at curl 1
constexpr double kThumbAbductDeg = 50.0;                  // swing under the palm at opposition 1

// Joint orientation from the bone direction and the flexion axis: -Z along the bone, X = flexion axis
// (orthogonalized), Y = Z x X is then the back of the bone, right-handed.
Quat joint_orientation(const Vec3& bone_dir, const Vec3& flex_axis) {
  Vec3 z = -bone_dir.normalized();
  Vec3 x = (flex_axis - flex_axis.dot(z) * z).normalized();
  Mat3 m;
  m.col(0) = x;
  m.col(1) = z.cross(x);
  m.col(2) = z;
  return Quat(m).normalized();
}

void set_joint(HandFrame& f, int j, const Vec3& p, const Vec3& dir, const Vec3& axis, double r) {
  f.joints[j].position = p;
  f.joints[j].orientation = joint_orientation(dir, axis);
  f.joints[j].radius = r;
  f.joints[j].valid = true;
}

// Flexion turns the bone towards the palm side: a rotation about the flexion axis by -angle
// (about +X by +angle would turn -Z towards +Y, the back of the hand).
Quat flexion(const Vec3& axis, double angle) { return Quat(Eigen::AngleAxisd(-angle, axis.normalized())); }

void build_finger(const FingerSpec& fs, double curl, double spread, double s, HandFrame& f) {
  Vec3 base = s * fs.base, knuckle = s * fs.knuckle;
  set_joint(f, fs.first_joint, base, knuckle - base, Vec3::UnitX(), s * fs.radius[0]);
  Quat spread_q(Eigen::AngleAxisd(fs.spread_deg * kDeg * spread, Vec3::UnitY()));
  Vec3 dir = spread_q * -Vec3::UnitZ();
  Vec3 axis = spread_q * Vec3::UnitX();
  Vec3 p = knuckle;
  for (int k = 0; k < 3; ++k) {
    dir = flexion(axis, curl * kFingerFlexDeg[k] * kDeg) * dir;
    set_joint(f, fs.first_joint + 1 + k, p, dir, axis, s * fs.radius[1 + k]);
    p += s * fs.length[k] * dir;
  }
  set_joint(f, fs.first_joint + 4, p, dir, axis, s * fs.radius[4]);
}

// The thumb's bones for given flexion angles and abduction (swing about the palm's Z axis under the palm): joint
// positions from the metacarpal to the tip, bone directions and the flexion axis. Positions only: the bisection
// in build_thumb needs the tip alone and so pays for no joint orientations (make_hand_frame is the per-frame
// cost of every simulated user's glove).
struct ThumbChain {
  std::array<Vec3, 4> p;
  std::array<Vec3, 3> dir;
  Vec3 axis;
};

ThumbChain thumb_chain(const std::array<double, 3>& flex, double abduct, double s) {
  Quat ab(Eigen::AngleAxisd(abduct, Vec3::UnitZ()));  // +Z rotation turns -X towards -Y: under the palm
  Vec3 dir = ab * kThumbDir.normalized();
  Vec3 nail = ab * kThumbNail;
  ThumbChain c;
  c.axis = nail.cross(-dir);  // X = Y x Z
  c.p[0] = s * kThumbBase;
  for (int k = 0; k < 3; ++k) {
    dir = flexion(c.axis, flex[k]) * dir;
    c.dir[k] = dir;
    c.p[k + 1] = c.p[k] + s * kThumbLength[k] * dir;
  }
  return c;
}

void build_thumb_chain(const std::array<double, 3>& flex, double abduct, double s, HandFrame& f) {
  const ThumbChain c = thumb_chain(flex, abduct, s);
  for (int k = 0; k < 3; ++k) set_joint(f, kThumbMetacarpal + k, c.p[k], c.dir[k], c.axis, s * kThumbRadius[k]);
  set_joint(f, kThumbTip, c.p[3], c.dir[2], c.axis, s * kThumbRadius[3]);
}

// Rigid rotation of the thumb joints about its carpometacarpal joint.
void rotate_thumb(const Quat& q, HandFrame& f) {
  Vec3 c = f.joints[kThumbMetacarpal].position;
  for (int j = kThumbMetacarpal; j <= kThumbTip; ++j) {
    f.joints[j].position = c + q * (f.joints[j].position - c);
    f.joints[j].orientation = (q * f.joints[j].orientation).normalized();
  }
}

// Thumb: curl flexes it across the palm; opposition swings it under the palm, flexes it just enough for its tip
// to reach the pad of the index tip (bisection on the distance from its base), then turns it onto that point.
void build_thumb(double curl, double opposition, double s, HandFrame& f) {
  auto flex_at = [](double lambda) {
    return std::array<double, 3>{kThumbFlexDeg[0] * kDeg * lambda, kThumbFlexDeg[1] * kDeg * lambda,
                                 kThumbFlexDeg[2] * kDeg * lambda};
  };
  double abduct = opposition * kThumbAbductDeg * kDeg;
  if (opposition <= 0) {
    build_thumb_chain(flex_at(curl), 0.0, s, f);
    return;
  }
  // Where the thumb tip centre sits when the two pads touch.
  const JointPose& it = f.joints[kIndexTip];
  Vec3 target = it.position - (it.radius + s * kThumbRadius[3]) * (it.orientation * Vec3::UnitY());
  Vec3 base = s * kThumbBase;
  double want = (target - base).norm();
  // Distance base->tip falls monotonically with flexion over [0, 1.3] (total bend stays below 180 degrees).
  double lo = 0, hi = 1.3;
  for (int it_count = 0; it_count < 50; ++it_count) {
    double mid = 0.5 * (lo + hi);
    ((thumb_chain(flex_at(mid), abduct, s).p[3] - base).norm() > want ? lo : hi) = mid;
  }
  double lambda = (1 - opposition) * curl + opposition * 0.5 * (lo + hi);
  build_thumb_chain(flex_at(lambda), abduct, s, f);
  Vec3 tip = f.joints[kThumbTip].position - base;
  Quat swing = Quat::FromTwoVectors(tip, target - base);
  rotate_thumb(Quat::Identity().slerp(opposition, swing), f);
}

// Mirror x -> -x. For a frame R (a rotation), M R M with M = diag(-1, 1, 1) is again a rotation whose Y and Z
// axes are the mirrored Y and Z axes: the quaternion (x, y, z, w) becomes (x, -y, -z, w).
void mirror(HandFrame& f) {
  for (JointPose& j : f.joints) {
    j.position.x() = -j.position.x();
    j.orientation = Quat(j.orientation.w(), j.orientation.x(), -j.orientation.y(), -j.orientation.z());
  }
}

}  // namespace

HandFrame make_hand_frame(Handedness handedness, const Pose& palm_pose, const HandPoseParams& params) {
  if (handedness != Handedness::Left && handedness != Handedness::Right)
    validate::fail("handedness", "must be Left or Right");
  Pose palm = validate::body_pose(palm_pose, "palm_pose");
  for (int i = 0; i < 5; ++i) validate::finite(params.curl[i], "params.curl[" + std::to_string(i) + "]");
  validate::finite(params.thumb_opposition, "params.thumb_opposition");
  validate::finite(params.spread, "params.spread");
  validate::in_range(params.scale, 1e-6, 1e3, "params.scale", "");  // 1 um .. 200 m hands: finite joints
  const double s = params.scale;

  HandFrame f;
  f.handedness = Handedness::Right;
  set_joint(f, kPalm, Vec3::Zero(), -Vec3::UnitZ(), Vec3::UnitX(), s * 0.013);
  set_joint(f, kWrist, Vec3(0, 0, s * 0.045), -Vec3::UnitZ(), Vec3::UnitX(), s * 0.014);
  for (int k = 0; k < 4; ++k)
    build_finger(kFingers[k], std::clamp(params.curl[k + 1], 0.0, 1.0), params.spread, s, f);
  build_thumb(std::clamp(params.curl[0], 0.0, 1.0), std::clamp(params.thumb_opposition, 0.0, 1.0), s, f);

  if (handedness == Handedness::Left) mirror(f);
  f.handedness = handedness;
  for (JointPose& j : f.joints) {
    j.position = palm.transform(j.position);
    j.orientation = (palm.orientation * j.orientation).normalized();
  }
  return f;
}

HandFrame bind_frame(Handedness handedness, double scale) {
  HandPoseParams p;
  p.scale = scale;
  return make_hand_frame(handedness, Pose{}, p);
}

HandPoseParams open_grip(const HandPoseParams& grip, double openness) {
  validate::in_range(openness, 0, 1, "openness", "");
  HandPoseParams p = grip;
  for (double& c : p.curl) c *= 1 - openness;
  p.thumb_opposition *= 1 - openness;
  return p;
}

HandPoseParams closing_grip(const HandPoseParams& grip, double t, double duration) {
  validate::finite(t, "t");
  if (!(duration > 0) || !std::isfinite(duration)) validate::fail("duration", "must be finite and > 0 s, got " + validate::fmt(duration));
  const double s = std::clamp(t / duration, 0.0, 1.0);
  const double closed = s * s * s * (10 - 15 * s + 6 * s * s);  // minimum jerk (Flash & Hogan)
  return open_grip(grip, 1 - closed);
}

// OpenXR joint radii are a finger's half width (mm to 2 cm), but adapters derive them from whatever a
// recording says (a fuzzed Leap document gives 0.25 m): a radius is a length like any other, up to 1e7 m.
constexpr double kMaxJointRadius = validate::kMaxCoordinate;

namespace {

// The same conditions as validate_frame's named checks, without building their argument names: a good joint
// (every joint of every step, normally) costs no allocation; a bad one falls through to the named checks.
// Every comparison is false for a NaN and each bound for an infinity (an infinite coefficient makes the norm
// infinite), so the bounds also prove every number finite: no separate finiteness pass.
bool joint_is_good(const JointPose& jp) {
  const Vec3& p = jp.position;
  constexpr double far = validate::kMaxCoordinate;
  return std::abs(p.x()) <= far && std::abs(p.y()) <= far && std::abs(p.z()) <= far &&
         std::abs(jp.orientation.norm() - 1.0) <= validate::kQuatTolerance && jp.radius >= 0 &&
         jp.radius <= kMaxJointRadius;
}

}  // namespace

bool joints_are_good(const HandFrame& frame) {
  for (const JointPose& jp : frame.joints)
    if (jp.valid && !joint_is_good(jp)) return false;
  return true;
}

#ifdef HANDSIM_AVX2_KERNELS
// Whether every valid joint is good (joint_is_good) four joints at a time: each lane the same comparisons of the
// same numbers (the quaternion's norm as Eigen's, sqrt((x x + z z) + (y y + w w)); |a| <= b as -b <= a <= b,
// false alike for a NaN), so the same answer.
namespace {
__attribute__((target("avx2"))) bool joints_are_good_avx2(const HandFrame& frame) {
  using simd4::V4;
  typedef long long Mask __attribute__((vector_size(32)));
  const auto& J = frame.joints;
  constexpr double far = validate::kMaxCoordinate;
  Mask bad = Mask{0, 0, 0, 0};
  for (int first = 0; first < kHandJointCount; first += 4) {
    const int k[4] = {first, first + 1, std::min(first + 2, kHandJointCount - 1),
                      std::min(first + 3, kHandJointCount - 1)};
    V4 x = simd4::load(J[k[0]].orientation.coeffs().data()), y = simd4::load(J[k[1]].orientation.coeffs().data()),
       z = simd4::load(J[k[2]].orientation.coeffs().data()), w = simd4::load(J[k[3]].orientation.coeffs().data());
    simd4::transpose(x, y, z, w);
    V4 px = simd4::load(J[k[0]].position.data()), py = simd4::load(J[k[1]].position.data()),
       pz = simd4::load(J[k[2]].position.data()), unused = simd4::load(J[k[3]].position.data());
    simd4::transpose(px, py, pz, unused);
    const V4 r{J[k[0]].radius, J[k[1]].radius, J[k[2]].radius, J[k[3]].radius};
    const Mask valid{-J[k[0]].valid, -J[k[1]].valid, -J[k[2]].valid, -J[k[3]].valid};
    const V4 d = simd4::sqrt((x * x + z * z) + (y * y + w * w)) - 1.0;
    const Mask good = (-far <= px) & (px <= far) & (-far <= py) & (py <= far) & (-far <= pz) & (pz <= far) &
                      (-validate::kQuatTolerance <= d) & (d <= validate::kQuatTolerance) & (r >= 0) &
                      (r <= kMaxJointRadius);
    bad |= valid & ~good;
  }
  return (bad[0] | bad[1] | bad[2] | bad[3]) == 0;
}
}  // namespace
#endif

bool frame_is_valid(const HandFrame& frame) {
  if (frame.handedness != Handedness::Left && frame.handedness != Handedness::Right) return false;
#ifdef HANDSIM_AVX2_KERNELS
  if (simd4::has_avx2()) return joints_are_good_avx2(frame);
#endif
  return joints_are_good(frame);
}

void validate_frame(const HandFrame& frame, const std::string& argument) {
  if (frame.handedness != Handedness::Left && frame.handedness != Handedness::Right)
    validate::fail(argument + ".handedness", "must be Left or Right");
  for (int j = 0; j < kHandJointCount; ++j) {
    const JointPose& jp = frame.joints[j];
    if (!jp.valid || joint_is_good(jp)) continue;  // untracked joints may hold anything
    std::string name = argument + ".joints[" + std::to_string(j) + "]";
    validate::point(jp.position, name + ".position");
    validate::unit_quat(jp.orientation, name + ".orientation");
    validate::in_range(jp.radius, 0, kMaxJointRadius, name + ".radius", "m");
  }
}

}  // namespace handsim
