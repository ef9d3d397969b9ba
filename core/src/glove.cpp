// The simulated users' data glove (glove.h). Its arithmetic is that of the Python glove it replaced
// (python/handsim/users.py before this file), operation for operation, so a seed gives the same frames:
// tests/python/test_glove.py checks it against that reference on made-up input.
#include "handsim/glove.h"

#include "python_quat.h"
#include "validate.h"

#include <algorithm>
#include <cmath>
#include <string>

namespace handsim {
namespace {

constexpr double kFingerTau = 1.0;  // s: finger sensors drift over seconds (IMU glove bend sensors)
constexpr double kPalmTau = 0.7;    // s: a user corrects a palm offset it sees within about a second
constexpr double kYawTau = 1.0;     // s: heading drift of an IMU without a magnetometer fix, over seconds

void finite_normals(const double* z, int n) {
  for (int i = 0; i < n; ++i) validate::finite(z[i], "z[" + std::to_string(i) + "]");
}

// The intended palm turned by `yaw` about the world's vertical (+Y) and shifted by `offset`: the Python glove's
// quat_mul(axis_angle([0, 1, 0], yaw), q), normalized as numpy normalized it.
Pose drifted_palm(const Pose& palm, const Vec3& offset, double yaw) {
  namespace pq = python_quat;
  const Quat& b = palm.orientation;
  const pq::Q q = pq::normalized_like_numpy(pq::mul(pq::axis_angle({0.0, 1.0, 0.0}, yaw), {b.x(), b.y(), b.z(), b.w()}));
  return {palm.position + offset, Quat(q[3], q[0], q[1], q[2])};
}

}  // namespace

template <int N>
Glove::Drift<N> Glove::make_drift(double sigma, double tau, double dt) {
  Drift<N> d;
  d.sigma = sigma;
  d.a = std::exp(-dt / tau);
  d.b = sigma * std::sqrt(1 - d.a * d.a);  // keeps the stationary std at sigma
  return d;
}

template <int N>
std::array<double, N> Glove::advanced(const Drift<N>& d, const double*& z) {
  std::array<double, N> x = d.x;
  if (d.sigma > 0)
    for (int i = 0; i < N; ++i) x[i] = d.a * x[i] + d.b * *z++;
  return x;
}

Glove::Glove(Handedness handedness, const GloveNoise& noise, double scale, double dt)
    : handedness_(handedness), noise_(noise), scale_(scale) {
  if (handedness != Handedness::Left && handedness != Handedness::Right)
    validate::fail("handedness", "must be Left or Right");
  validate::non_negative(noise.finger_noise, "noise.finger_noise");
  validate::non_negative(noise.finger_drift, "noise.finger_drift");
  validate::non_negative(noise.palm_noise, "noise.palm_noise");
  validate::non_negative(noise.palm_drift, "noise.palm_drift");
  validate::non_negative(noise.yaw_drift, "noise.yaw_drift");
  validate::in_range(scale, 1e-6, 1e3, "scale", "");  // make_hand_frame's range
  validate::time_step(dt, "dt");
  fingers_ = make_drift<7>(noise.finger_drift, kFingerTau, dt);
  palm_ = make_drift<3>(noise.palm_drift, kPalmTau, dt);
  yaw_ = make_drift<1>(noise.yaw_drift, kYawTau, dt);
}

int Glove::start_normals() const { return fingers_.normals() + palm_.normals() + yaw_.normals(); }

// The drifts' variates, then 7 finger-noise and 3 palm-jitter variates, in the Python glove's order.
int Glove::frame_normals() const { return start_normals() + 7 + 3; }

void Glove::start(const double* z) {
  finite_normals(z, start_normals());
  for (int i = 0; i < fingers_.normals(); ++i) fingers_.x[i] = 0.0 + fingers_.sigma * *z++;
  for (int i = 0; i < palm_.normals(); ++i) palm_.x[i] = 0.0 + palm_.sigma * *z++;
  for (int i = 0; i < yaw_.normals(); ++i) yaw_.x[i] = 0.0 + yaw_.sigma * *z++;
}

HandFrame Glove::frame(const Pose& palm, const HandPoseParams& shape, bool tracked, const double* z) {
  validate::body_pose(palm, "palm");
  for (int i = 0; i < 5; ++i) validate::finite(shape.curl[i], "shape.curl[" + std::to_string(i) + "]");
  validate::finite(shape.thumb_opposition, "shape.thumb_opposition");
  validate::finite(shape.spread, "shape.spread");
  finite_normals(z, frame_normals());

  const std::array<double, 7> fingers = advanced(fingers_, z);
  const std::array<double, 3> offset = advanced(palm_, z);
  const std::array<double, 1> yaw = advanced(yaw_, z);
  double n[7];  // drift + white noise, as numpy's normal(0, std) gives it: 0 + std * z
  for (int i = 0; i < 7; ++i) n[i] = fingers[i] + (0.0 + noise_.finger_noise * *z++);
  Vec3 shift;
  for (int i = 0; i < 3; ++i) shift[i] = offset[i] + (0.0 + noise_.palm_noise * *z++);

  HandFrame out = untracked_frame(handedness_);
  if (tracked) {
    HandPoseParams p;
    for (int i = 0; i < 5; ++i) p.curl[i] = std::min(std::max(shape.curl[i] + n[i], 0.0), 1.0);
    p.thumb_opposition = std::min(std::max(shape.thumb_opposition + n[5], 0.0), 1.0);
    p.spread = std::min(std::max(shape.spread + 0.5 * n[6], -0.5), 1.0);
    p.scale = scale_;
    out = make_hand_frame(handedness_, drifted_palm(palm, shift, yaw[0]), p);
  }
  fingers_.x = fingers;  // only now: a throw above leaves the glove as it was
  palm_.x = offset;
  yaw_.x = yaw;
  return out;
}

HandFrame untracked_frame(Handedness handedness) {
  HandFrame f;
  f.handedness = handedness;
  for (JointPose& j : f.joints) j.valid = false;
  return f;
}

}  // namespace handsim
