#include "grasp.h"

#include "validate.h"

#include <algorithm>
#include <cmath>
#include <numeric>
#include <string>

namespace handsim {
namespace {

// Pruning margins (radians / dot units). They only make the exact pair scan look at a few more pairs (or skip
// a quick reject), so they trade speed, never correctness, against rounding in acos and the products.
constexpr double kAngleMargin = 1e-9;
constexpr double kDotMargin = 1e-12;

void check_directions(const std::vector<Vec3>& d) {
  for (size_t i = 0; i < d.size(); ++i) {
    double n2 = d[i].squaredNorm();
    if (!(std::abs(n2 - 1.0) <= 1e-6))  // also catches NaN
      validate::fail("directions[" + std::to_string(i) + "]",
                     "must be a unit vector, got " + validate::fmt(d[i]));
  }
}

// O(n): the extreme directions along an axis are the likeliest opposing pair; test it.
bool extremes_oppose(const std::vector<Vec3>& d, const Vec3& axis, double c, OpposingPair* pair) {
  size_t lo = 0, hi = 0;
  for (size_t i = 1; i < d.size(); ++i) {
    double s = d[i].dot(axis);
    if (s < d[lo].dot(axis)) lo = i;
    if (s > d[hi].dot(axis)) hi = i;
  }
  if (!(lo != hi && d[lo].dot(d[hi]) < c)) return false;
  if (pair) *pair = {lo, hi};
  return true;
}

// O(n): if every direction lies within angle alpha of the axis, every pair is within 2*alpha, so every
// d_i . d_j >= cos(2 alpha) = 2 cos^2(alpha) - 1 (when alpha <= 90 deg). True when that rules out d_i . d_j < c.
bool cone_excludes(const std::vector<Vec3>& d, const Vec3& axis, double c) {
  double cos_alpha = 1.0;
  for (const Vec3& di : d) cos_alpha = std::min(cos_alpha, di.dot(axis));
  return cos_alpha > 0 && 2 * cos_alpha * cos_alpha - 1 >= c + kDotMargin;
}

// Exact scan. theta_i = angle of d_i to the axis; the angle between d_i and d_j is at most theta_i + theta_j,
// so d_i . d_j < c needs theta_i + theta_j > acos(c). With the thetas sorted in decreasing order, each row of
// the scan stops at the first partner too close to the axis, and the whole scan stops at the first empty row.
// With `parts`, pairs of one part are skipped (the bound does not depend on the parts, so it still prunes).
bool scan_pairs(const std::vector<Vec3>& d, const Vec3& axis, double c, const std::vector<int>* parts = nullptr,
                OpposingPair* pair = nullptr) {
  const size_t n = d.size();
  std::vector<double> theta(n);
  for (size_t i = 0; i < n; ++i) theta[i] = std::acos(std::clamp(d[i].dot(axis), -1.0, 1.0));
  std::vector<size_t> order(n);
  std::iota(order.begin(), order.end(), size_t{0});
  std::sort(order.begin(), order.end(), [&](size_t a, size_t b) { return theta[a] > theta[b]; });
  const double needed = std::acos(std::clamp(c, -1.0, 1.0)) - kAngleMargin;
  for (size_t a = 0; a + 1 < n; ++a) {
    const size_t i = order[a];
    if (theta[i] + theta[order[a + 1]] <= needed) return false;
    for (size_t b = a + 1; b < n && theta[i] + theta[order[b]] > needed; ++b)
      if ((!parts || (*parts)[i] != (*parts)[order[b]]) && d[i].dot(d[order[b]]) < c) {
        if (pair) *pair = {i, order[b]};
        return true;
      }
  }
  return false;
}

// The mean direction; a mean that nearly cancels (directions all around) is no useful axis, x is as good as
// any then.
Vec3 mean_axis(const std::vector<Vec3>& d) {
  Vec3 mean = Vec3::Zero();
  for (const Vec3& di : d) mean += di;
  return mean.norm() > 1e-6 * double(d.size()) ? Vec3(mean.normalized()) : Vec3(Vec3::UnitX());
}

}  // namespace

bool opposing_contacts(const std::vector<Vec3>& directions, double c, OpposingPair* pair) {
  validate::finite(c, "c");
  check_directions(directions);
  const auto& d = directions;
  if (d.size() < 2) return false;
  if (c > 1.0 + kDotMargin) {  // every pair qualifies
    if (pair) *pair = {0, 1};
    return true;
  }
  const Vec3 axis = mean_axis(d);
  for (const Vec3& a : {axis, Vec3(Vec3::UnitX()), Vec3(Vec3::UnitY()), Vec3(Vec3::UnitZ())})
    if (extremes_oppose(d, a, c, pair)) return true;
  if (cone_excludes(d, axis, c)) return false;
  return scan_pairs(d, axis, c, nullptr, pair);
}

bool opposing_across_parts(const std::vector<Vec3>& directions, const std::vector<int>& parts, double c) {
  if (parts.size() != directions.size())
    validate::fail("parts", "must have one label per direction, got " + std::to_string(parts.size()) + " for " +
                                std::to_string(directions.size()));
  if (!opposing_contacts(directions, c)) return false;  // validates; most frames end here
  if (c > 1.0 + kDotMargin) return std::any_of(parts.begin(), parts.end(), [&](int p) { return p != parts[0]; });
  return scan_pairs(directions, mean_axis(directions), c, &parts);
}

void validate_grasp_settings(const GraspSettings& s, const std::string& prefix) {
  // A cosine: beyond +-1 every threshold means "never" resp. "any two parts" (opposing_contacts), so +-2
  // keeps both settings and rejects only nonsense such as 1e308.
  validate::in_range(s.cos_threshold, -2, 2, prefix + "cos_threshold", "");
  // Times up to an hour, distances up to 1 m (a hand is 0.2 m long): beyond is a unit mix-up.
  validate::in_range(s.grasp_time_s, 0, 3600, prefix + "grasp_time_s", "s");
  validate::in_range(s.release_time_s, 0, 3600, prefix + "release_time_s", "s");
  validate::in_range(s.closing_distance, 0, 1, prefix + "closing_distance", "m");
  validate::in_range(s.closing_window_s, 0, 3600, prefix + "closing_window_s", "s");
  validate::in_range(s.opening_distance, 0, 1, prefix + "opening_distance", "m");
  validate::in_range(s.release_distance, 0, 1, prefix + "release_distance", "m");
  validate::in_range(s.tracking_grace_s, 0, 3600, prefix + "tracking_grace_s", "s");
  if (s.velocity_window < 2 || s.velocity_window > 1000)
    validate::fail(prefix + "velocity_window", "must be in 2..1000 frames, got " + std::to_string(s.velocity_window));
}

// ---------------------------------------------------------------------------------------------------------
// GraspTracker

GraspTracker::GraspTracker(const GraspSettings& settings) : settings_(settings) {
  validate_grasp_settings(settings);
}

void GraspTracker::reset() {
  state_ = GraspState::Free;
  grasp_streak_ = open_streak_ = 0;
  untracked_s_ = 0;
  tightest_ = 0;
}

GraspEvent GraspTracker::update(const GraspInput& in) {
  validate::time_step(in.dt, "dt");
  if (in.contact_count < 0) validate::fail("contact_count", "must be >= 0, got " + std::to_string(in.contact_count));
  return state_ == GraspState::Free ? update_free(in) : update_grasped(in);
}

// A streak of `time` s has lasted `needed`; the slack keeps 2 frames of 1/60 s from falling short of 1/30 s.
static bool lasted(double time, double needed) { return time >= needed - 1e-9; }

GraspEvent GraspTracker::update_free(const GraspInput& in) {
  // An untracked hand's contacts are stale: it cannot start a grasp, and it breaks a streak.
  bool condition = in.hand_tracked && in.opposing && in.contact_count >= 2 && in.closing;
  grasp_streak_ = condition ? grasp_streak_ + in.dt : 0;
  if (!condition || !lasted(grasp_streak_, settings_.grasp_time_s)) return {};
  state_ = GraspState::Grasped;
  grasp_streak_ = open_streak_ = 0;
  untracked_s_ = 0;
  tightest_ = in.span;
  return {GraspEventType::GraspBegin, ReleaseReason::None, false};
}

GraspEvent GraspTracker::update_grasped(const GraspInput& in) {
  if (!in.hand_tracked) {
    // Hold through short dropouts; the open-hand streak is frozen, not reset, since nothing was observed.
    untracked_s_ += in.dt;
    return untracked_s_ > settings_.tracking_grace_s ? end(ReleaseReason::TrackingLost) : GraspEvent{};
  }
  untracked_s_ = 0;
  tightest_ = std::min(tightest_, in.span);
  const bool opened = settings_.opening_distance > 0 && in.span > tightest_ + settings_.opening_distance;
  const bool holding = in.opposing && in.contact_count >= 2 && !opened;
  open_streak_ = holding ? 0 : open_streak_ + in.dt;
  return !holding && lasted(open_streak_, settings_.release_time_s) ? end(ReleaseReason::Released) : GraspEvent{};
}

GraspEvent GraspTracker::end(ReleaseReason reason) {
  reset();
  return {GraspEventType::GraspEnd, reason, reason == ReleaseReason::TrackingLost};
}

// ---------------------------------------------------------------------------------------------------------
// Grip span and its history

double grip_span(const HandModel& model, const std::array<BoneTransform, kHandJointCount>& bones) {
  auto joint = [&](int j) { return Vec3(bones[j] * model.bind_inverse[j].inverse().position.homogeneous()); };
  const Vec3 palm = joint(kPalm);
  double span = (joint(kThumbTip) - joint(kIndexTip)).norm();
  for (int tip : {kIndexTip, kMiddleTip, kRingTip, kLittleTip}) span += (joint(tip) - palm).norm();
  return span;
}

void GripHistory::push(double span, const Vec3& palm, double time, double window) {
  validate::finite(span, "span");
  validate::finite(palm, "palm");
  validate::finite(time, "time");
  if (!samples_.empty() && !(time > samples_.back().time))
    validate::fail("time", "must increase, got " + validate::fmt(time) + " after " + validate::fmt(samples_.back().time));
  samples_.push_back({span, palm, time});
  size_t old = 0;
  while (old + 1 < samples_.size() && samples_[old].time < time - window - 1e-9) ++old;
  samples_.erase(samples_.begin(), samples_.begin() + std::ptrdiff_t(old));
}

bool GripHistory::in_time_order() const {
  for (size_t i = 1; i < samples_.size(); ++i)
    if (!(samples_[i].time > samples_[i - 1].time)) return false;
  return true;
}

double GripHistory::closed_by() const {
  double widest = 0;
  for (const Sample& s : samples_) widest = std::max(widest, s.span);
  return samples_.empty() ? 0.0 : widest - samples_.back().span;
}

double GripHistory::approached_by(const GripHistory& other) const {
  // Both hands are pushed at each step's end time, so shared times are equal bit for bit.
  double widest = -1, now = -1;
  size_t j = other.samples_.size();
  for (size_t i = samples_.size(); i-- > 0 && j > 0;) {
    while (j > 0 && other.samples_[j - 1].time > samples_[i].time) --j;
    if (j == 0 || other.samples_[j - 1].time != samples_[i].time) continue;
    const double d = (samples_[i].palm - other.samples_[j - 1].palm).norm();
    if (now < 0) now = d;
    widest = std::max(widest, d);
  }
  return now < 0 ? 0.0 : widest - now;
}

// ---------------------------------------------------------------------------------------------------------
// HandMotionHistory

HandMotionHistory::HandMotionHistory(int window) {
  if (window < 2) validate::fail("window", "must be >= 2, got " + std::to_string(window));
  samples_.resize(static_cast<size_t>(window));
}

void HandMotionHistory::push(const Pose& palm, double time) {
  Pose p = validate::pose(palm, "palm");
  validate::finite(time, "time");
  if (count_ > 0 && !(time > sample(0).time))
    validate::fail("time", "must increase, got " + validate::fmt(time) + " after " + validate::fmt(sample(0).time));
  samples_[static_cast<size_t>(next_)] = {p, time};
  next_ = (next_ + 1) % window();
  count_ = std::min(count_ + 1, window());
}

bool HandMotionHistory::in_time_order() const {
  for (int age = 1; age < count_; ++age)
    if (!(sample(age - 1).time > sample(age).time)) return false;
  return true;
}

const HandMotionHistory::Sample& HandMotionHistory::sample(int age) const {
  int w = window();
  return samples_[static_cast<size_t>(((next_ - 1 - age) % w + w) % w)];
}

// Times are taken relative to the newest sample so long sessions (t ~ 1e5 s) keep sub-microsecond spacing.
double HandMotionHistory::mean_time_offset() const {
  double sum = 0;
  for (int k = 0; k < count_; ++k) sum += sample(k).time - sample(0).time;
  return sum / count_;
}

double HandMotionHistory::time_spread() const {
  double mean = mean_time_offset(), s = 0;
  for (int k = 0; k < count_; ++k) {
    double tau = sample(k).time - sample(0).time - mean;
    s += tau * tau;
  }
  return s;
}

// Least-squares slope of x(t): sum (tau_k - mean) x_k / sum (tau_k - mean)^2, with x_k relative to the newest.
Vec3 HandMotionHistory::linear_velocity() const {
  if (!has_velocity()) return Vec3::Zero();
  double mean = mean_time_offset();
  Vec3 num = Vec3::Zero();
  for (int k = 0; k < count_; ++k)
    num += (sample(k).time - sample(0).time - mean) * (sample(k).pose.position - sample(0).pose.position);
  return num / time_spread();
}

// Same slope for the rotation vectors r_k = log(q_k q_newest^-1). Under a constant world-frame angular
// velocity, q_k = exp(w tau_k) q_newest, so r_k = w tau_k exactly and the slope is w.
Vec3 HandMotionHistory::angular_velocity() const {
  if (!has_velocity()) return Vec3::Zero();
  double mean = mean_time_offset();
  Quat newest_inv = sample(0).pose.orientation.conjugate();
  Vec3 num = Vec3::Zero();
  for (int k = 0; k < count_; ++k)
    num += (sample(k).time - sample(0).time - mean) * rotation_vector(Quat(sample(k).pose.orientation * newest_inv));
  return num / time_spread();
}

Vec3 HandMotionHistory::point_velocity(const Vec3& world_point) const {
  validate::finite(world_point, "world_point");
  if (!has_velocity()) return Vec3::Zero();
  return linear_velocity() + angular_velocity().cross(world_point - sample(0).pose.position);
}

BodyVelocity HandMotionHistory::attached_body_velocity(const Vec3& centre_of_mass) const {
  return {point_velocity(centre_of_mass), angular_velocity()};
}

int rigid_part(const HandModel& model, int p) {
  int k = 0;
  model.particle_weights.col(p).maxCoeff(&k);
  const int bone = model.particle_bones(k, p);
  switch (bone) {
    case kWrist: case kThumbMetacarpal: case kIndexMetacarpal: case kMiddleMetacarpal: case kRingMetacarpal:
    case kLittleMetacarpal:
      return kPalm;
    case kThumbTip: case kIndexTip: case kMiddleTip: case kRingTip: case kLittleTip:
      return bone - 1;
    default:
      return bone;
  }
}

}  // namespace handsim
