#include "grasp.h"

#include "validate.h"
#include "world_impl.h"

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

// The bone particle p moves with most (its largest skinning weight).
int main_bone(const HandModel& model, int p) {
  int k = 0;
  model.particle_weights.col(p).maxCoeff(&k);
  return model.particle_bones(k, p);
}

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

}  // namespace

bool can_squeeze(int a, int b) {
  auto finger = [](int part) { return part >= kIndexMetacarpal ? (part - kIndexMetacarpal) / 5 : -1; };
  return a != b && !(finger(a) >= 0 && finger(b) >= 0 && finger(a) != finger(b));
}

namespace {

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

GraspSettings GraspSettings::contacts() {
  GraspSettings s;
  s.closing_distance = 0;
  s.opening_distance = 0;
  s.pinch_reach = 0;
  return s;
}

GraspSettings GraspSettings::paper() {
  GraspSettings s = contacts();
  s.cos_threshold = kPaperLiteralCos;
  s.across_parts = false;
  s.grasp_time_s = 0;
  s.release_time_s = 0;
  return s;
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
  validate::in_range(s.pinch_reach, 0, 1, prefix + "pinch_reach", "m");
  validate::in_range(s.opening_distance, 0, 1, prefix + "opening_distance", "m");
  validate::in_range(s.squeeze_distance, 0, 1, prefix + "squeeze_distance", "m");
  validate::in_range(s.pass_depth, 0, 1, prefix + "pass_depth", "m");
  validate::in_range(s.release_distance, 0, 1, prefix + "release_distance", "m");
  validate::in_range(s.slip_distance, 0, 1, prefix + "slip_distance", "m");
  validate::in_range(s.tracking_grace_s, 0, 3600, prefix + "tracking_grace_s", "s");
  if (s.velocity_window < 2 || s.velocity_window > 1000)
    validate::fail(prefix + "velocity_window", "must be in 2..1000 frames, got " + std::to_string(s.velocity_window));
  validate::in_range(s.velocity_window_s, 0, 1, prefix + "velocity_window_s", "s");
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

double capsule_gap(const Vec3& a0, const Vec3& a1, double ra0, double ra1, const Vec3& b0, const Vec3& b1, double rb0,
                   double rb1) {
  // The closest points a0 + s u, b0 + t v (s, t in 0..1): s from the two lines' normal equations, t the best for that
  // s, then s the best for that t, each clamped (Ericson, Real-Time Collision Detection 5.1.9, with s always re-taken).
  // A segment shorter than ~1 nm is a point; (nearly) parallel ones start from s = 0.
  const Vec3 u = a1 - a0, v = b1 - b0, w = a0 - b0;
  const double uu = u.dot(u), vv = v.dot(v), uv = u.dot(v), uw = u.dot(w), vw = v.dot(w);
  const double den = uu * vv - uv * uv;
  auto unit = [](double x) { return std::clamp(x, 0.0, 1.0); };
  constexpr double kTiny = 1e-18;
  double s = den > kTiny ? unit((uv * vw - vv * uw) / den) : 0.0;
  const double t = vv > kTiny ? unit((uv * s + vw) / vv) : 0.0;
  s = uu > kTiny ? unit((uv * t - uw) / uu) : 0.0;
  return (w + s * u - t * v).norm() - (ra0 + s * (ra1 - ra0)) - (rb0 + t * (rb1 - rb0));
}

GripBind grip_bind(const HandModel& model) {
  GripBind b;
  for (int j = 0; j < kHandJointCount; ++j) {
    b.joint[j] = model.bind_inverse[j].inverse().position;
    b.radius[j] = model.bind.joints[j].radius;
  }
  return b;
}

GripTerms grip_terms(const HandModel& model, const std::array<BoneTransform, kHandJointCount>& bones, double pinch_reach) {
  return grip_terms(grip_bind(model), bones, pinch_reach);
}

GripTerms grip_terms(const GripBind& bind, const std::array<BoneTransform, kHandJointCount>& bones, double pinch_reach) {
  auto joint = [&](int j) { return Vec3(bones[j] * bind.joint[j].homogeneous()); };
  auto radius = [&](int j) { return bind.radius[j]; };
  const Vec3 palm = joint(kPalm);
  GripTerms terms;
  terms[kThumbTerm] = pinch_reach > 0
                          ? std::min(pinch_reach, capsule_gap(joint(kThumbDistal), joint(kThumbTip), radius(kThumbDistal),
                                                              radius(kThumbTip), joint(kIndexDistal), joint(kIndexTip),
                                                              radius(kIndexDistal), radius(kIndexTip)))
                          : (joint(kThumbTip) - joint(kIndexTip)).norm();
  int term = kThumbTerm + 1;
  for (int tip : {kIndexTip, kMiddleTip, kRingTip, kLittleTip}) terms[term++] = (joint(tip) - palm).norm();
  return terms;
}

namespace {
double sum_of(const GripTerms& terms, unsigned which = ~0u) {
  double sum = 0;  // the thumb's term first, then the fingers': the order the span was always summed in
  for (size_t i = 0; i < terms.size(); ++i)
    if (which & (1u << i)) sum += terms[i];
  return sum;
}
}  // namespace

double grip_span(const HandModel& model, const std::array<BoneTransform, kHandJointCount>& bones, double pinch_reach) {
  return sum_of(grip_terms(model, bones, pinch_reach));
}

unsigned touching_terms(const HandModel& model, const std::vector<ParticleContact>& contacts) {
  unsigned terms = 0;
  for (const ParticleContact& c : contacts) {
    const int part = rigid_part(model, c.particle);  // kPalm or a phalanx
    if (part > kThumbMetacarpal && part <= kThumbTip) {
      terms |= 1u << kThumbTerm;
    } else if (part > kIndexMetacarpal && part <= kLittleTip) {
      const int finger = (part - kIndexMetacarpal) / 5;  // index .. little
      terms |= 1u << (kThumbTerm + 1 + finger);
      if (finger == 0) terms |= 1u << kThumbTerm;  // the thumb's term is the gap to the index
    }
  }
  return terms;
}

double hand_length(const HandModel& model) {
  return (model.bind_inverse[kMiddleTip].inverse().position - model.bind_inverse[kWrist].inverse().position).norm();
}

void GripHistory::push(const GripTerms& terms, const Vec3& palm, double time, double window) {
  for (double term : terms) validate::finite(term, "span");
  validate::finite(palm, "palm");
  samples_.push(Sample{terms, palm, time}, window);
}

bool GripHistory::in_time_order() const { return samples_.in_time_order(); }

double GripHistory::span() const { return samples_.empty() ? 0.0 : sum_of(samples_.back().terms); }

double GripHistory::closed_by(unsigned terms) const {
  if (samples_.empty() || terms == 0) return 0.0;
  double widest = 0;
  samples_.for_each([&](const Sample& s) { widest = std::max(widest, sum_of(s.terms, terms)); });
  return widest - sum_of(samples_.back().terms, terms);
}

double GripHistory::palms_apart(const GripHistory& other) const {
  if (samples_.empty() || other.samples_.empty()) return 0.0;
  return (samples_.back().palm - other.samples_.back().palm).norm();
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

namespace {
// How many of `count` samples (time_of(age), age 0 the newest) a slope over `span` seconds uses: the newest back to
// the first one at least span old, at least two (span 0: all). Tracker timestamps come in microseconds, and a 60 Hz
// clock summed in doubles reaches 0.05 s a few ulps short: a sample a microsecond younger than span counts as that
// old, so 60 Hz always gives 4 samples for 0.05 s, not 4 or 5 by rounding.
template <class TimeOf>
int newest_in_span(int count, double span, const TimeOf& time_of) {
  if (!(span > 0)) return count;
  constexpr double kTimestampResolution = 1e-6;
  const double newest = time_of(0);
  int n = 2;
  while (n < count && newest - time_of(n - 1) < span - kTimestampResolution) ++n;
  return n;
}

// A least-squares slope against time over the samples of ages 0..n-1 (time_of(age), age 0 the newest): calls
// add(age, tau) with each sample's time centred on their mean and returns the sum of tau^2, so the slope of any
// x is the sum of tau x_age that `add` gathers divided by it. One place for the palm's velocities and a point's.
template <class TimeOf, class Add>
double centred_times(int n, const TimeOf& time_of, const Add& add) {
  const double newest = time_of(0);
  double sum = 0;
  for (int k = 0; k < n; ++k) sum += time_of(k) - newest;
  const double mean = sum / n;
  double spread = 0;
  for (int k = 0; k < n; ++k) {
    const double tau = time_of(k) - newest - mean;
    spread += tau * tau;
    add(k, tau);
  }
  return spread;
}
}  // namespace

// ---------------------------------------------------------------------------------------------------------
// Squeeze: the hand's articulation carrying an opposing pair into the body

void ArticulationHistory::push(const Bones& bones, double time, double window) {
  // The bones as the 312 doubles they are stored as, which the compiler copies as a block (Eigen's assignment of
  // 26 fixed matrices copied them one double at a time).
  static_assert(sizeof(Bones) == kHandJointCount * 12 * sizeof(double));
  samples_.push_made(time, window, [&bones](Sample& s) {
    std::copy_n(bones.front().data(), kHandJointCount * 12, s.bones.front().data());
  });
}

bool ArticulationHistory::in_time_order() const { return samples_.in_time_order(); }

namespace {
// x -> B^-1 x for a rigid B = [R | t].
Vec3 to_bind(const BoneTransform& b, const Vec3& x) { return b.leftCols<3>().transpose() * (x - b.col(3)); }
Vec3 to_world(const BoneTransform& b, const Vec3& x) { return b.leftCols<3>() * x + b.col(3); }
}  // namespace

Vec3 ArticulationHistory::point_velocity(const HandModel& model, int particle, const Vec3& position, double span,
                                         int most) const {
  const int count = std::min(static_cast<int>(samples_.size()), most);
  if (count < 2) return Vec3::Zero();
  auto sample = [&](int age) -> const Sample& { return samples_[samples_.size() - 1 - static_cast<size_t>(age)]; };
  auto time_of = [&](int age) { return sample(age).time; };
  const int bone = main_bone(model, particle);
  const Vec3 rest = to_bind(sample(0).bones[bone], position);  // the point in its bone's bind frame
  Vec3 slope = Vec3::Zero();
  const double spread = centred_times(newest_in_span(count, span, time_of), time_of, [&](int age, double tau) {
    slope += tau * (to_world(sample(age).bones[bone], rest) - position);
  });
  return slope / spread;
}

double ArticulationHistory::inward(const HandModel& model, int particle, const Vec3& position,
                                   const Vec3& normal) const {
  if (samples_.size() < 2) return 0.0;
  const Bones& now = samples_.back().bones;
  const int bone = main_bone(model, particle);
  const Vec3 rest = to_bind(now[bone], position);      // the particle in its bone's bind frame
  const Vec3 in_palm = to_bind(now[kPalm], position);  // ... and in the palm's, now
  const Vec3 inwards = -(now[kPalm].leftCols<3>().transpose() * normal);  // into the body, palm coordinates
  double most = 0;
  for (size_t k = 0; k + 1 < samples_.size(); ++k) {
    const Bones& then = samples_[k].bones;
    most = std::max(most, (in_palm - to_bind(then[kPalm], to_world(then[bone], rest))).dot(inwards));
  }
  return most;
}

bool squeezing_pair(const std::vector<Vec3>& directions, const std::vector<int>& parts,
                    const std::vector<double>& inward, double c, double needed) {
  validate::finite(c, "c");
  validate::finite(needed, "needed");
  check_directions(directions);
  const size_t n = directions.size();
  if (inward.size() != n || (!parts.empty() && parts.size() != n))
    validate::fail("inward", "must have one value per direction (and parts one label each or none), got " +
                                 std::to_string(inward.size()) + " and " + std::to_string(parts.size()) + " for " +
                                 std::to_string(n));
  std::vector<size_t> order(n);
  std::iota(order.begin(), order.end(), size_t{0});
  std::sort(order.begin(), order.end(), [&](size_t a, size_t b) { return inward[a] > inward[b]; });
  for (size_t a = 0; a + 1 < n; ++a) {
    const size_t i = order[a];
    if (inward[i] + inward[order[a + 1]] < needed) return false;  // every later pair sums to less
    for (size_t b = a + 1; b < n && inward[i] + inward[order[b]] >= needed; ++b) {
      const size_t j = order[b];
      if ((parts.empty() || can_squeeze(parts[i], parts[j])) && directions[i].dot(directions[j]) < c) return true;
    }
  }
  return false;
}

// ---------------------------------------------------------------------------------------------------------
// HandMotionHistory

HandMotionHistory::HandMotionHistory(int window, double span) : span_(span) {
  if (window < 2) validate::fail("window", "must be >= 2, got " + std::to_string(window));
  if (!(span >= 0)) validate::non_negative(span, "span");
  samples_.resize(static_cast<size_t>(window));
}

void HandMotionHistory::push(const Pose& palm, double time) {
  const Pose p = validate::is_pose(palm) ? Pose{palm.position, palm.orientation.normalized()}  // as pose() returns it
                                         : validate::pose(palm, "palm");
  if (!std::isfinite(time)) validate::finite(time, "time");
  if (count_ > 0 && !(time > sample(0).time))
    validate::fail("time", "must increase, got " + validate::fmt(time) + " after " + validate::fmt(sample(0).time));
  samples_[static_cast<size_t>(next_)] = {p, time};
  next_ = (next_ + 1) % window();
  count_ = std::min(count_ + 1, window());
  stale_ = true;
}

// Least-squares slopes over the samples, with times taken relative to the newest sample so long sessions
// (t ~ 1e5 s) keep sub-microsecond spacing: sum (tau_k - mean) x_k / sum (tau_k - mean)^2, x_k relative to the
// newest. Linear: x_k the palm positions. Angular: the rotation vectors r_k = log(q_k q_newest^-1); under a
// constant world-frame angular velocity, q_k = exp(w tau_k) q_newest, so r_k = w tau_k exactly and the slope is
// w. One pass for both, at the first read after a push.
int HandMotionHistory::samples_in_span() const {
  return newest_in_span(count_, span_, [this](int age) { return sample(age).time; });
}

const std::pair<Vec3, Vec3>& HandMotionHistory::slopes() const {
  if (!stale_) return slopes_;
  stale_ = false;
  if (!has_velocity()) {
    slopes_ = {Vec3::Zero(), Vec3::Zero()};
    return slopes_;
  }
  const Sample& newest = sample(0);
  const Quat newest_inv = newest.pose.orientation.conjugate();
  Vec3 linear = Vec3::Zero(), angular = Vec3::Zero();
  const double spread =
      centred_times(samples_in_span(), [this](int age) { return sample(age).time; }, [&](int age, double tau) {
        const Sample& s = sample(age);
        linear += tau * (s.pose.position - newest.pose.position);
        angular += tau * rotation_vector(Quat(s.pose.orientation * newest_inv));
      });
  slopes_ = {linear / spread, angular / spread};
  return slopes_;
}

void HandMotionHistory::clear() {
  count_ = 0;
  stale_ = true;
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

Vec3 HandMotionHistory::point_velocity(const Vec3& world_point) const {
  validate::finite(world_point, "world_point");
  if (!has_velocity()) return Vec3::Zero();
  return linear_velocity() + angular_velocity().cross(world_point - sample(0).pose.position);
}

BodyVelocity HandMotionHistory::attached_body_velocity(const Vec3& centre_of_mass) const {
  return {point_velocity(centre_of_mass), angular_velocity()};
}

int rigid_part(const HandModel& model, int p) {
  const int bone = main_bone(model, p);
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

namespace {
// A held or released body's velocity never exceeds the cap every caller's velocity is held to (1e4 m/s,
// rad/s): the direction is kept, the magnitude capped.
Vec3 capped_speed(const Vec3& v) {
  const double n = v.norm();
  return n > validate::kMaxSpeed ? Vec3(v * (validate::kMaxSpeed / n)) : v;
}
// A held body that static geometry pushed back by `pushed` does not move on into it: the part of its velocity
// into the surface is taken out, the part along it kept (it slides with the hand).
BodyVelocity stopped_velocity(BodyVelocity v, const Vec3& pushed) {
  const double n = pushed.norm();
  if (n == 0) return v;
  const Vec3 out = pushed / n;
  v.linear -= std::min(0.0, v.linear.dot(out)) * out;
  return v;
}

// The span a hand must have closed by lately to begin a grasp; 0 (off) is met by any hand.
double closing_needed(const WorldDef& def) { return def.grasp.closing_distance; }

using Intent = GraspScratch::Intent;
bool witness_opposes(const HandBodyPair& pair, double cos);

// Whether the hand closes onto the body, for a grasp to begin (GraspSettings::closing_distance): the digits that
// touch the body closed, their terms of the grip span (touching_terms) shrank by closing_distance within the
// window. A digit squeezes a body only by closing onto it; digits closing elsewhere press nothing. Two palms
// clapping on a box (Leap recording three-claps) flex the fingers a little and bring the thumb towards the index:
// the whole span closes 15-33 mm, the digits on the box (the little finger, the ring finger) 2-6 mm. A held body
// (not a begin) needs no closing: its tracker (GraspTracker::update_grasped) reads none, and only its own update
// changes whether it holds, so the window is not scanned for it (closed_by: 31 samples at 60 Hz, every frame of
// a hold) and the answer is "met".
bool closes_on(const WorldDef& def, const HandSlot& h, const HandBodyPair& pair, bool begin) {
  const double needed = closing_needed(def);
  if (!begin) return true;
  if (needed <= 0) return h.grip.closed_by() >= needed;
  return h.grip.closed_by(touching_terms(*h.model, pair.contacts)) >= needed;
}

// Eq. 3 for one hand on one body, and whether the hand has been closing (GraspSettings::closing_distance).
// A grasp begins with two rigid parts (GraspSettings::across_parts), counting only contacts within pass_depth and,
// with squeeze_distance, only a pair the hand's articulation carried into the body; any opposing pair keeps it,
// so a held body's contacts (hundreds on a pinched lid) need no parts. A held body is kept by the existence of
// one opposing pair, so the pair that kept it last frame is tried first: while thumb and finger still oppose
// (nearly every frame of a hold), the answer is known after one dot product instead of a pass over every
// contact, and it is the same answer (the full test is exact). `directions` and `parts` are scratch space.
Intent hand_intent(const WorldDef& def, const std::vector<HandSlot>& hands, HandBodyPair& pair, uint32_t hi,
                   std::vector<Vec3>& directions, std::vector<int>& parts) {
  const GraspSettings& g = def.grasp;
  const HandSlot& h = hands[hi];
  const bool begin = !pair.tracker.grasped();
  const bool across = g.across_parts && begin;
  const bool every_contact = !begin || (g.pass_depth <= 0 && g.squeeze_distance <= 0);  // no begin-only filter
  Intent out;
  out.closing = closes_on(def, h, pair, begin);
  if (!across && every_contact && witness_opposes(pair, g.cos_threshold)) {
    out.opposing = true;
    return out;
  }
  auto counts = [&](const ParticleContact& c) { return !begin || g.pass_depth <= 0 || c.depth <= g.pass_depth; };
  directions.clear();
  parts.clear();
  for (const ParticleContact& c : pair.contacts) {
    if (!counts(c)) continue;  // a pass-through, not a grip
    directions.push_back(c.normal);
    if (across) parts.push_back(rigid_part(*h.model, c.particle));
  }
  OpposingPair found{0, 0};
  out.opposing = directions.size() >= 2 && (across ? opposing_across_parts(directions, parts, g.cos_threshold)
                                                   : opposing_contacts(directions, g.cos_threshold, &found));
  pair.witness = {-1, -1};
  if (out.opposing && !across && every_contact)  // found indexes directions, here one per contact
    pair.witness = {pair.contacts[found.first].particle, pair.contacts[found.second].particle};
  if (out.opposing && begin && g.squeeze_distance > 0) {  // only when eq. 3 holds: it looks back over the window
    std::vector<double> inward;
    for (const ParticleContact& c : pair.contacts)
      if (counts(c))
        inward.push_back(h.articulation.inward(*h.model, c.particle, h.state.tracked_positions.col(c.particle), c.normal));
    out.opposing = squeezing_pair(directions, parts, inward, g.cos_threshold, g.squeeze_distance);
  }
  return out;
}

// Whether the two particles of the pair's last opposing pair both still touch and still oppose.
bool witness_opposes(const HandBodyPair& pair, double cos) {
  if (pair.witness[0] < 0 || pair.witness[0] == pair.witness[1]) return false;
  auto find = [&](int particle) -> const ParticleContact* {  // contacts are sorted by particle
    auto it = std::lower_bound(pair.contacts.begin(), pair.contacts.end(), particle,
                               [](const ParticleContact& c, int p) { return c.particle < p; });
    return it != pair.contacts.end() && it->particle == particle ? &*it : nullptr;
  };
  const ParticleContact* a = find(pair.witness[0]);
  const ParticleContact* b = a ? find(pair.witness[1]) : nullptr;
  return b && a->normal.dot(b->normal) < cos;
}

// Eq. 3 across two hands touching one body: a contact of one opposes a contact of the other.
bool hands_oppose(const WorldDef& def, const HandBodyPair& a, const HandBodyPair& b, std::vector<Vec3>& directions,
                  std::vector<int>& parts) {
  directions.clear();
  parts.clear();
  for (const ParticleContact& c : a.contacts) directions.push_back(c.normal), parts.push_back(0);
  for (const ParticleContact& c : b.contacts) directions.push_back(c.normal), parts.push_back(1);
  return opposing_across_parts(directions, parts, def.grasp.cos_threshold);
}

}  // namespace

// --- lines 4-9, 11-13, 16: per object, collect contacts by hand and decide grasps (eq. 3) ---
StageReport decide_grasps(Grasps& grasps, GraspScratch& scratch, double dt) {
  const WorldDef& def = grasps.def;
  std::vector<Body>& bodies = grasps.bodies;
  const std::vector<HandSlot>& hands = grasps.hands;
  HandBodyPairs& pairs = grasps.pairs;
  std::vector<Event>& events = grasps.events;
  std::vector<Vec3>& directions = scratch.directions;
  std::vector<int>& parts = scratch.parts;
  std::vector<Intent>& alone = scratch.intents;  // per pair in map order: eq. 3 and closing of its hand by itself
  alone.clear();
  for (auto& [key, pair] : pairs) {
    alone.push_back(bodies[key.second].manipulable() ? hand_intent(def, hands, pair, key.first, directions, parts)
                                                     : Intent{});
    pair.opposing_alone = alone.back().opposing;
  }
  int decided = 0;
  size_t k = 0;
  for (auto it = pairs.begin(); it != pairs.end(); ++k) {
    const uint32_t hi = it->first.first, bi = it->first.second;
    HandBodyPair& pair = it->second;
    Body& b = bodies[bi];
    const HandId hand = grasps.hand_id(hi);
    const int count = int(pair.contacts.size());
    if (count > 0 && pair.previous_count == 0) events.push_back({EventType::ContactBegin, hand, grasps.body_id(bi)});
    if (count == 0 && pair.previous_count > 0) events.push_back({EventType::ContactEnd, hand, grasps.body_id(bi)});
    pair.previous_count = count;
    if (b.manipulable()) {
      const HandSlot& h = hands[hi];
      const Intent own = alone[k];
      Intent intent = own;
      // Two hands squeezing one body (two flat palms on a big box): eq. 3 across the hands, closing as the
      // palms approach each other. Each hand alone has its contacts on one face only. A hand that holds the
      // body by itself needs no partner, and does not lend one: a finger of the other hand still resting on
      // a body it handed over is no grip (SecondHandSlipsThenTakesOverWithoutAJump). Only with the closing
      // rule: without it, two open hands flapping about a cube (Leap recording flapping) grasped it. And only a
      // body too big for one hand: palms farther apart than the hand is long (hand_length). Two open palms
      // clapping on a 5 cm cube (Leap recording three-claps, Leap's grab and pinch 0) are no grip; one hand
      // grips a body that small.
      if (!own.opposing && closing_needed(def) > 0)
        for (const auto& [other, other_pair] : pairs)
          if (other.second == bi && other.first != hi && !other_pair.contacts.empty() && !other_pair.opposing_alone &&
              !other_pair.appeared_inside &&
              hands[other.first].state.tracked && h.grip.palms_apart(hands[other.first].grip) > hand_length(*h.model) &&
              hands_oppose(def, pair, other_pair, directions, parts)) {
            intent.opposing = true;
            intent.closing = own.closing || h.grip.approached_by(hands[other.first].grip) >= closing_needed(def);
            if (intent.closing) break;
          }
      if (pair.appeared_inside) intent.closing = false;  // never seen closing onto it (HandBodyPair::appeared_inside)
      const GraspEvent e =
          pair.tracker.update({intent.opposing, count, h.state.tracked, dt, intent.closing, h.grip.span()});
      if (e.type == GraspEventType::GraspEnd) {
        grasps.end_grasp(hi, bi, e.reason == ReleaseReason::TrackingLost ? EventReason::TrackingLost : EventReason::Released,
                  e.zero_velocity, count > 0);
        pair.let_go = def.push_model == PushModel::Wrap;  // its overlap now is the grip's (HandBodyPair::let_go)
      }
      // A hand whose grasp found both places taken (a third hand) joins as soon as one frees up.
      if (pair.tracker.grasped() && !b.held_by(hi)) grasps.begin_grasp(hi, bi);
      if (pair.tracker.grasped()) pair.let_go = false;
      ++decided;
    }
    // Forget pairs with nothing going on, so the map holds only what touches or holds.
    if (count == 0 && !pair.tracker.grasped()) it = pairs.erase(it);
    else ++it;
  }
  if (decided == 0) return stage_skipped(SkipReason::NoMovableBodyTouched);
  return stage_work(decided);
}

void Grasps::begin_grasp(uint32_t hi, uint32_t bi) {
  Body& b = bodies[bi];
  const HandSlot& h = hands[hi];
  if (!b.grasp.grasped) {
    b.grasp = {true, hand_id(hi), HandId{}, h.palm.inverse() * b.pose};
    moving.held.push_back(bi);
    // A free body is attached to the hand, and moves with it from this frame. A joint's child is not: the hand only
    // tells the joint where it wants the child (hard: solve_joints; soft: a velocity drive against the Bullet
    // constraint).
    if (!b.jointed() && b.soft_joint < 0) {
      set_motion(backend, moving, b, BodyMotion::Kinematic);
      follow_hand(def, bodies, hands, boxes, stop_scratch, b);
    }
  } else if (b.grasp.primary.index != hi && b.grasp.secondary.is_null()) {
    b.grasp.secondary = hand_id(hi);
    b.secondary_relative = h.palm.inverse() * b.pose;
  } else {
    return;  // a third hand on the same body: the two holding it keep it
  }
  events.push_back({EventType::GraspBegin, hand_id(hi), body_id(bi)});
}

void Grasps::end_grasp(uint32_t hi, uint32_t bi, EventReason reason, bool zero_velocity, bool touching) {
  Body& b = bodies[bi];
  if (!b.held_by(hi)) return;
  if (b.grasp.primary.index != hi) {
    b.grasp.secondary = HandId{};
  } else if (b.jointed() && b.grasp.secondary.is_null() && !zero_velocity && touching) {
    // A hard joint's child let go of: the grasp's end is seen at the end of this frame, through which the hand held
    // the grip, so the joint solve still carries the child to where its hand holds it now, and it leaves from there
    // with its hand's motion (solve_joints; free after it: finish_releases), as a released free body starts from its
    // hand's pose now (below). Freed where the last held frame left it, the child lagged its hand by one frame's
    // motion, so which frame happened to see the grip open decided how far it went (docs/grasp.md "Under Wrap"). Only
    // a hand still touching it held it through the frame: one whose contacts vanished (a tracker jump carrying the
    // hand away) did not.
    moving.letting_go.push_back(bi);
  } else if (b.jointed() || b.soft_joint >= 0) {
    // A joint's child is never teleported to the hand: the other hand takes over where the child is, or the joint
    // keeps the velocity the hand gave it (a soft joint's drive; a hand whose tracking or contacts are lost held
    // nothing through this frame).
    if (!b.grasp.secondary.is_null()) hand_over(b);
    else b.grasp = GraspInfo();
  } else {
    // A released body starts from where its hand holds it now, with the velocity of that point, and a body handed
    // over starts from there too. In a step the attach stage put it there already, before the contacts (the same
    // pose again); between steps it is where the last step's hand left it.
    follow_hand(def, bodies, hands, boxes, stop_scratch, b);
    if (!b.grasp.secondary.is_null()) hand_over(b);
    else release(b, zero_velocity ? BodyVelocity{} : BodyVelocity{b.linear, b.angular});
  }
  events.push_back({EventType::GraspEnd, hand_id(hi), body_id(bi), reason});
}

// The children let go of this step (end_grasp), carried to their hand's pose by the joint solve, are free from here;
// one that a second hand grasped in the same step is that hand's.
void Grasps::finish_releases() {
  for (uint32_t bi : moving.letting_go) {
    Body& b = bodies[bi];
    if (!b.grasp.grasped) continue;
    if (!b.grasp.secondary.is_null()) hand_over(b);
    else b.grasp = GraspInfo();
  }
  moving.letting_go.clear();
}

// The secondary hand becomes primary, taking the body from where it is: no jump. A free body moves with it from
// this frame.
void Grasps::hand_over(Body& b) {
  b.grasp.primary = b.grasp.secondary;
  b.grasp.secondary = HandId{};
  b.grasp.primary_relative = hands[b.grasp.primary.index].palm.inverse() * b.pose;
  if (!b.jointed() && b.soft_joint < 0) follow_hand(def, bodies, hands, boxes, stop_scratch, b);
}

void Grasps::release(Body& b, const BodyVelocity& velocity) {
  b.grasp = GraspInfo();
  b.just_released = true;
  moving.released.push_back(uint32_t(&b - bodies.data()));
  b.linear = capped_speed(velocity.linear);
  b.angular = capped_speed(velocity.angular);
  set_motion(backend, moving, b, BodyMotion::Dynamic);
  backend.write(b.backend, b.pose, b.linear, b.angular);
}

// A held body moved by the caller stays held where it now is.
void Grasps::retake_relative_poses(Body& b) {
  if (!b.grasp.grasped) return;
  b.grasp.primary_relative = hands[b.grasp.primary.index].palm.inverse() * b.pose;
  if (!b.grasp.secondary.is_null()) b.secondary_relative = hands[b.grasp.secondary.index].palm.inverse() * b.pose;
}

void Grasps::end_pair(uint32_t hi, uint32_t bi, EventReason reason) {
  auto it = pairs.find({hi, bi});
  if (bodies[bi].held_by(hi)) end_grasp(hi, bi, reason, true);
  if (it != pairs.end() && it->second.previous_count > 0)
    events.push_back({EventType::ContactEnd, hand_id(hi), body_id(bi)});
}

void follow_hand(const WorldDef& def, std::vector<Body>& bodies, const std::vector<HandSlot>& hands,
                 const BodyBoxes& boxes, StaticStopScratch& scratch, Body& b) {
  const HandSlot& h = hands[b.grasp.primary.index];
  Vec3 pushed;
  b.pose = held_pose(def, bodies, boxes, hands, scratch, b, &pushed);
  const BodyVelocity v = stopped_velocity(h.history.attached_body_velocity(b.pose.position), pushed);
  b.linear = capped_speed(v.linear);  // a body held far from a fast-turning palm: omega x r unbounded
  b.angular = capped_speed(v.angular);
}

// --- lines 10, 14: a grasped object keeps its pose relative to its primary hand (stopped by static geometry:
// static_stop.cpp) ---
StageReport follow_primary_hands(const WorldDef& def, const std::vector<uint32_t>& held, std::vector<Body>& bodies,
                                 const std::vector<HandSlot>& hands, const BodyBoxes& boxes, StaticStopScratch& scratch) {
  int following = 0;
  for (uint32_t bi : held) {
    Body& b = bodies[bi];
    if (b.jointed() || b.soft_joint >= 0) continue;
    follow_hand(def, bodies, hands, boxes, scratch, b);
    ++following;
  }
  if (following == 0) return stage_skipped(SkipReason::NothingGrasped);
  return stage_work(following);
}

// --- line 20: the second hand's relative pose is re-taken every frame (eq. 5) ---
StageReport retake_secondary_hands(const std::vector<uint32_t>& held, std::vector<Body>& bodies,
                                   const std::vector<HandSlot>& hands) {
  int slipping = 0;
  for (uint32_t bi : held) {
    Body& b = bodies[bi];
    if (b.grasp.secondary.is_null()) continue;
    b.secondary_relative = hands[b.grasp.secondary.index].palm.inverse() * b.pose;
    ++slipping;
  }
  if (slipping == 0) return stage_skipped(SkipReason::NoSecondHand);
  return stage_work(slipping);
}

}  // namespace handsim
