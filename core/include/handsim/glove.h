// The data glove of the simulated users (python/handsim/users.py, docs/experiments.md): between what a user
// means to do in a frame (a palm pose and a hand shape) and the hand frame the world gets, it adds the errors of
// the IMU glove the paper's subjects wore -- finger-sensor noise and slow drift, palm jitter and residual drift,
// heading drift -- and drops frames while tracking is lost. It is the per-frame hot path of a simulated trial,
// so it lives here rather than in Python (docs/performance.md, "Sweeps").
//
// The glove draws no random numbers itself: the caller passes standard normal variates, so a user's whole
// trial follows from one seeded generator on the caller's side (numpy's, for the Python users) and the same
// seed gives the same frames on every runner.
#pragma once

#include "handsim/hand.h"

namespace handsim {

// The sizes of the glove's errors (every one >= 0; 0 turns that error off).
struct GloveNoise {
  double finger_noise = 0;  // per-frame finger-sensor noise, std (curl / opposition units)
  double finger_drift = 0;  // slow finger drift, stationary std (same units; Ornstein-Uhlenbeck, tau 1 s)
  double palm_noise = 0;    // per-frame palm-position jitter, std per axis (m)
  double palm_drift = 0;    // residual palm drift the user does not correct, stationary std per axis (m; OU, tau 0.7 s)
  double yaw_drift = 0;     // residual heading drift about the vertical, stationary std (rad; OU, tau 1 s)
};

class Glove {
 public:
  // Throws Error naming "noise.<field>" (negative or not finite), "scale" (the hand size, as
  // HandPoseParams::scale) or "dt" (the frame time, s). The drifts start at 0 until start() draws them.
  Glove(Handedness handedness, const GloveNoise& noise, double scale, double dt);

  // How many standard normal variates start() and frame() each take: a drift of size 0 takes none.
  int start_normals() const;
  int frame_normals() const;

  // Draws the drifts from their stationary distribution (a glove already worn for a while).
  // `z`: start_normals() variates. Throws Error naming "z" when one is not finite.
  void start(const double* z);

  // The next frame: advances the drifts by one frame time, adds drift and noise to the intended `palm` pose and
  // finger `shape` (its curls, thumb_opposition and spread; the glove's scale replaces shape.scale) and returns
  // make_hand_frame's frame, or one with every joint invalid when not `tracked` (the drifts advance either
  // way, as the sensors keep running). `z`: frame_normals() variates. Throws Error naming "palm", "shape.*" or
  // "z" and then leaves the glove as it was.
  HandFrame frame(const Pose& palm, const HandPoseParams& shape, bool tracked, const double* z);

  // The current drifts: 5 curls, thumb opposition and spread; palm offset (m); heading (rad).
  const std::array<double, 7>& finger_drift() const { return fingers_.x; }
  const std::array<double, 3>& palm_drift() const { return palm_.x; }
  double yaw_drift() const { return yaw_.x[0]; }

 private:
  // Ornstein-Uhlenbeck noise of stationary std `sigma` and time constant `tau`, per component.
  template <int N>
  struct Drift {
    double sigma = 0, a = 0, b = 0;
    std::array<double, N> x{};
    int normals() const { return sigma > 0 ? N : 0; }
  };
  template <int N>
  static Drift<N> make_drift(double sigma, double tau, double dt);
  template <int N>
  static std::array<double, N> advanced(const Drift<N>& d, const double*& z);

  Handedness handedness_;
  GloveNoise noise_;
  double scale_;
  Drift<7> fingers_;
  Drift<3> palm_;
  Drift<1> yaw_;
};

// A frame whose joints are all invalid: the tracker lost the hand.
HandFrame untracked_frame(Handedness handedness);

}  // namespace handsim
