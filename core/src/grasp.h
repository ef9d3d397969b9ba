// Grasp decision (Kim & Park, Section II-B, eq. 3) and what the world needs around it: hysteresis so a
// jittery hand neither grabs nor drops objects by accident, tolerance of short tracking losses, and the hand
// velocity that a released object is thrown with.
#pragma once

#include "handsim/grasp_settings.h"
#include "handsim/types.h"
#include "handsim/hand.h"
#include "pose_fit.h"
#include "validate.h"

#include <algorithm>
#include <array>
#include <type_traits>
#include <utility>

#include <vector>

namespace handsim {

// True when some pair i != j has d_i . d_j < c. `directions` must be unit vectors (|d|^2 within 1e-6 of 1);
// throws handsim::Error otherwise or when c is not finite. Exact: same answer as the all-pairs test.
// Cost: O(n) for the common cases (an opposing pair among the extremes along 4 axes is found at once; all
// directions inside a cone narrower than acos(c)/2 are rejected at once); otherwise O(n log n) sorting plus
// a pair scan pruned by the angle to the mean direction, O(n^2) only for adversarial rings of directions.
// `pair`, when given and the answer is true, receives the indices of one opposing pair (i != j).
using OpposingPair = std::pair<size_t, size_t>;
bool opposing_contacts(const std::vector<Vec3>& directions, double c = kOpposingCos, OpposingPair* pair = nullptr);

// Whether two rigid parts (rigid_part's labels: kPalm or a phalanx's joint) can squeeze a body between them
// (squeezing_pair): not one part (it cannot squeeze), and not the phalanges of two different fingers: the index to little fingers flex
// in parallel, so they press the same way and cannot clamp a body between them (fingertips of an open hand lying
// on two faces of a lid's edge are no grip). The thumb opposes the palm and every finger; one finger's phalanges
// oppose each other when it hooks round an edge.
bool can_squeeze(int a, int b);

// opposing_contacts restricted to pairs whose parts differ (parts[i] labels directions[i], same length).
// Checks the unrestricted test first (O(n) in the common cases), then the pruned pair scan, skipping pairs of one part.
bool opposing_across_parts(const std::vector<Vec3>& directions, const std::vector<int>& parts,
                           double c = kOpposingCos);

enum class GraspState { Free, Grasped };
enum class GraspEventType { None, GraspBegin, GraspEnd };
enum class ReleaseReason { None, Released, TrackingLost };

struct GraspEvent {
  GraspEventType type = GraspEventType::None;
  ReleaseReason reason = ReleaseReason::None;  // set for GraspEnd only
  // GraspEnd only: the hand's velocity is unknown (tracking lost), so release the object at rest rather than
  // throwing it with a stale velocity.
  bool zero_velocity = false;
};

// One frame of one (hand, object) pair, as the world's contact pass sees it.
struct GraspInput {
  bool opposing = false;    // opposing_contacts() over this pair's penetration directions
  int contact_count = 0;    // particles of this hand touching the object (>= 0)
  bool hand_tracked = true; // HandFrame::tracked()
  double dt = 0;            // frame duration (s), finite and > 0
  bool closing = true;      // the hand closed lately (GripHistory::closed_by >= closing_distance)
  double span = 0;          // the hand's grip span now (m, grip_span); for opening_distance
};

// The grasp state machine of one (hand, object) pair.
//  Free -> Grasped: tracked, opposing, >= 2 contacts and closing for grasp_time_s (consecutive frames).
//  Grasped -> Free (Released): tracked without an opposing pair, or with the hand opened by more than
//    opening_distance over its tightest span since the grasp began, for release_time_s.
//    The world counts a held object's contacts within GraspSettings::release_distance of its surface, so
//    fingers that slide on it or jitter off it by less than that keep it; fingers that open further drop it,
//    even while one finger or the palm still touches it (a box resting against the index after the thumb
//    has opened is no longer held: waiting for every contact to vanish would glue it to the hand).
//  Grasped -> Free (TrackingLost, zero_velocity): the hand stays untracked for longer than tracking_grace_s.
//    While untracked within the grace time the grasp holds and contact counts (stale) are ignored.
class GraspTracker {
 public:
  explicit GraspTracker(const GraspSettings& settings = {});

  GraspEvent update(const GraspInput& input);  // throws handsim::Error on bad input, state unchanged
  void reset();                                // back to Free, counters cleared

  GraspState state() const { return state_; }
  bool grasped() const { return state_ == GraspState::Grasped; }
  double untracked_time() const { return untracked_s_; }
  const GraspSettings& settings() const { return settings_; }

  // What the tracker carries from frame to frame, for save, restore and the state hash (world_state.cpp);
  // the settings are the world's, not state.
  template <class Visitor, class Self>
  static void visit_state(Self& t, Visitor& v) {
    v.enumeration(t.state_, GraspState::Grasped);
    v.state(t.grasp_streak_);
    v.state(t.open_streak_);
    v.state(t.tightest_);
    v.state(t.untracked_s_);
  }

 private:
  GraspEvent update_free(const GraspInput& in);
  GraspEvent update_grasped(const GraspInput& in);
  GraspEvent end(ReleaseReason reason);

  GraspSettings settings_;
  GraspState state_ = GraspState::Free;
  double grasp_streak_ = 0;  // time (s) of consecutive frames meeting the grasp condition (Free)
  double open_streak_ = 0;   // time (s) of consecutive tracked frames without a hold (Grasped)
  double tightest_ = 0;      // the smallest grip span since the grasp began (Grasped)
  double untracked_s_ = 0;  // time since tracking was lost (Grasped)
};

// The rigid part of the hand particle p moves with (GraspSettings::across_parts): its most weighted bone, with
// the palm, the wrist and the five metacarpals as one part (kPalm) and a tip as part of its distal bone. The
// thumb's metacarpal (the ball of the thumb) counts as palm: a flat palm pressed 3-10 mm down onto a box
// touched opposite faces with it and the palm; the thumb opposes with its phalanges.
int rigid_part(const HandModel& model, int particle);

// The gap (m) between the surfaces of two tapered capsules: round the segment a0 -> a1 with a radius changing
// linearly from ra0 to ra1 along it, and round b0 -> b1 with rb0 .. rb1: the distance between the segments'
// closest points less the two radii there; < 0 where the capsules overlap. Exact for constant radii; with a taper
// the surfaces' closest points lie off the axes', and the result exceeds the least gap by at most the radii's
// change along the two bones (1.4 mm for the default hand's thumb and index pads; CapsuleGap tests), as Python's
// closure strengths have always measured it. A finger's pad is such a capsule round its distal -> tip bone with the
// joint radii, so two of them give how far apart the pads are (Python's skeleton.pulp_gap calls this). A segment
// may be a point.
double capsule_gap(const Vec3& a0, const Vec3& a1, double ra0, double ra1, const Vec3& b0, const Vec3& b1, double rb0,
                   double rb1);

// The grip span of a hand (m): the four fingertips' distances to the palm joint plus the thumb's term, at the joints
// of `bones` (skinning's B_j) and the model's bind pose. The thumb's term with pinch_reach > 0
// (GraspSettings::pinch_reach) is the gap of the thumb's and the index's pads (capsule_gap round their distal -> tip
// bones, the model's joint radii), at most pinch_reach; with 0 the thumb tip's distance to the index tip. Closing a
// grab or a pinch shortens it; moving or turning the hand as a whole does not change it.
double grip_span(const HandModel& model, const std::array<BoneTransform, kHandJointCount>& bones, double pinch_reach);
// The grip span's five terms, summed by grip_span: the thumb's (kThumbTerm), then the index, middle, ring and little
// fingertips' distances to the palm joint.
using GripTerms = std::array<double, 5>;
constexpr int kThumbTerm = 0;
GripTerms grip_terms(const HandModel& model, const std::array<BoneTransform, kHandJointCount>& bones, double pinch_reach);
// What grip_terms reads of the model: each joint's bind position (as the bones carry it: the inverse of
// bind_inverse, not the frame's position, which may differ in the last bit) and radius (the skin round the bones
// is the bind hand's). A hand slot makes it once (HandSlotModel::grip_bind), not 9 pose inverses a frame.
struct GripBind {
  std::array<Vec3, kHandJointCount> joint;
  std::array<double, kHandJointCount> radius;
};
GripBind grip_bind(const HandModel& model);
// grip_terms(model, ...) with grip_bind(model) made already: the same terms, bit for bit.
GripTerms grip_terms(const GripBind& bind, const std::array<BoneTransform, kHandJointCount>& bones, double pinch_reach);
// The grip span's terms (bit i: GripTerms[i]) of the digits `contacts` touch with, by rigid_part: a finger's own
// term when one of its phalanges touches, the thumb's term when the thumb's or the index finger's phalanges touch.
// The palm (with the metacarpals and the ball of the thumb) gives none: a digit closes onto a body it touches.
unsigned touching_terms(const HandModel& model, const std::vector<ParticleContact>& contacts);

// The hand's length in its bind pose (m): wrist joint to middle fingertip. Two hands squeeze a body only with their
// palms farther apart than this (decide_grasps): a body narrower than a hand is long is one hand's to grip.
double hand_length(const HandModel& model);

// Samples with a .time, oldest first, kept for the last `window` seconds (the newest is always kept): the grip and
// articulation histories share this. A ring: a push writes into the slot of the oldest sample dropped, so it copies
// the new sample once and moves none of the others (at 60 Hz a 0.5 s window holds 31; an articulation sample is 26
// bones, 2.5 kB, and the vector with its dropped samples in front moved one sample a push on average).
template <class Sample>
class SampleWindow {
 public:
  // Throws handsim::Error naming "time" unless times strictly increase.
  void push(Sample sample, double window) {
    push_made(sample.time, window, [&sample](Sample& slot) { slot = std::move(sample); });
  }
  // push of the sample `fill(Sample&)` writes in its slot, at `time` (no copy of a whole sample made first).
  template <class Fill> void push_made(double time, double window, Fill&& fill) {
    check_next(time);
    Sample& slot = next_slot();
    fill(slot);
    slot.time = time;
    ++size_;
    while (size_ > 1 && (*this)[0].time < time - window - 1e-9) drop_oldest();
  }
  void clear() {
    items_.clear();
    first_ = size_ = 0;
  }
  bool empty() const { return size_ == 0; }
  size_t size() const { return size_; }
  const Sample& operator[](size_t k) const { return items_[slot_of(k)]; }  // 0: the oldest
  const Sample& back() const { return (*this)[size_ - 1]; }
  // f(sample) for each sample held, oldest first: the ring's two runs, without a slot computed per sample.
  template <class F> void for_each(F&& f) const {
    const size_t run = std::min(size_, items_.size() - first_);
    for (size_t i = first_; i < first_ + run; ++i) f(items_[i]);
    for (size_t i = 0; i < size_ - run; ++i) f(items_[i]);
  }
  // Strictly increasing times, as push keeps them (a restored state is checked).
  bool in_time_order() const {
    for (size_t k = 1; k < size(); ++k)
      if (!((*this)[k].time > (*this)[k - 1].time)) return false;
    return true;
  }

  // The samples held, oldest first, as a list (save, restore and the hash: the bytes of a vector of them).
  template <class Visitor, class Self, class F>
  static void visit_state(Self& w, Visitor& v, F f) {
    if constexpr (std::is_const_v<Self>) {
      std::vector<Sample> held;
      held.reserve(w.size());
      for (size_t k = 0; k < w.size(); ++k) held.push_back(w[k]);
      v.list(held, f);
    } else {
      w.linearize();
      v.list(w.items_, f);
      w.size_ = w.items_.size();
    }
  }

 private:
  void check_next(double time) const {
    validate::finite(time, "time");
    if (!empty() && !(time > back().time))
      validate::fail("time", "must increase, got " + validate::fmt(time) + " after " + validate::fmt(back().time));
  }
  // The slot of the k-th oldest sample held.
  size_t slot_of(size_t k) const {
    const size_t i = first_ + k;
    return i < items_.size() ? i : i - items_.size();
  }
  // The slot after the newest: a dropped sample's, else a new one (the ring grows, rarely: to the most it held).
  Sample& next_slot() {
    if (size_ < items_.size()) return items_[slot_of(size_)];
    linearize();
    return items_.emplace_back();
  }
  void drop_oldest() {
    first_ = slot_of(1);
    --size_;
  }
  // The samples held at items_[0, size_), oldest first, and no other slot.
  void linearize() {
    std::rotate(items_.begin(), items_.begin() + std::ptrdiff_t(first_), items_.end());
    items_.resize(size_);
    first_ = 0;
  }
  std::vector<Sample> items_;  // the ring: size_ samples from items_[first_] on, wrapping at the end
  size_t first_ = 0, size_ = 0;
};

// A hand's bone transforms (skinning's B_j) over the last `window` seconds, for GraspSettings::squeeze_distance:
// how the hand's own articulation (flexing, opposing the thumb; not moving or turning the whole hand) moved its
// particles.
class ArticulationHistory {
 public:
  using Bones = std::array<BoneTransform, kHandJointCount>;
  // Times must increase (throws handsim::Error); samples older than the window before the newest are dropped.
  void push(const Bones& bones, double time, double window);
  void clear() { samples_.clear(); }
  // How far the articulation carried `particle` (now at `position`, on a contact with outward normal `normal`)
  // inwards through that face: the largest over the window of (y_now - y_then) . (-normal), with y the particle in
  // palm coordinates (its own bone's motion relative to the palm bone), turned into the world by the current palm.
  // 0 with fewer than two samples; a palm particle gives 0.
  double inward(const HandModel& model, int particle, const Vec3& position, const Vec3& normal) const;
  // The velocity of the point `position` carried by `particle`'s own bone (the palm's motion and the finger's
  // articulation together), measured as HandMotionHistory measures the palm's: the least-squares slope of its world
  // positions over the newest samples back to the first one at least `span` seconds old (at least two, at most
  // `most`; span 0: the newest `most`). Zero with fewer than two samples.
  Vec3 point_velocity(const HandModel& model, int particle, const Vec3& position, double span, int most) const;

  bool in_time_order() const;  // strictly increasing times, as push keeps them (a restored state is checked)

  template <class Visitor, class Self>
  static void visit_state(Self& a, Visitor& v) {
    SampleWindow<Sample>::visit_state(a.samples_, v, [&v](auto& s) {
      for (auto& bone : s.bones) v.state(bone);
      v.state(s.time);
    });
  }

 private:
  struct Sample {
    Sample() {}  // the bones left unset (not zeroed): push_made writes them
    Bones bones;
    double time = 0;
  };
  SampleWindow<Sample> samples_;
};

// Eq. 3 for a squeeze: some pair i != j with d_i . d_j < c, can_squeeze(parts[i], parts[j]) (all pairs when `parts`
// is empty)
// and inward[i] + inward[j] >= needed (ArticulationHistory::inward of each contact). Same lengths, unit directions;
// throws handsim::Error otherwise. Scans pairs in decreasing order of inward motion, stopping at the first sum
// below `needed`.
bool squeezing_pair(const std::vector<Vec3>& directions, const std::vector<int>& parts,
                    const std::vector<double>& inward, double c, double needed);

// A hand's grip span (its terms, grip_terms) and palm position over the last `window` seconds, for
// GraspSettings::closing_distance.
class GripHistory {
 public:
  // Times must increase (throws handsim::Error); samples older than the window before the newest are dropped.
  void push(const GripTerms& terms, const Vec3& palm, double time, double window);
  void clear() { samples_.clear(); }
  bool empty() const { return samples_.empty(); }
  double span() const;  // the newest sample's terms summed (grip_span)
  // How much the span shrank from its widest in the window to now (>= 0): closed_by every term.
  double closed_by() const { return closed_by(~0u); }
  // The same for the sum of the span's `terms` only (bit i: GripTerms[i], as touching_terms gives them); 0 without.
  double closed_by(unsigned terms) const;
  // How much the distance between this hand's palm and `other`'s shrank from its widest in the window to
  // now, over the samples both have at the same times (0 when they share none).
  double approached_by(const GripHistory& other) const;
  // The distance between this hand's palm and `other`'s in their newest samples (0 when either has none).
  double palms_apart(const GripHistory& other) const;

  bool in_time_order() const;  // strictly increasing times, as push keeps them (a restored state is checked)

  template <class Visitor, class Self>
  static void visit_state(Self& g, Visitor& v) {
    SampleWindow<Sample>::visit_state(g.samples_, v, [&v](auto& s) {
      for (auto& term : s.terms) v.state(term);
      v.state(s.palm);
      v.state(s.time);
    });
  }

 private:
  struct Sample {
    GripTerms terms{};  // the span is their sum (sum_of), not stored: one place for it
    Vec3 palm = Vec3::Zero();
    double time = 0;
  };
  SampleWindow<Sample> samples_;  // a few dozen at most
};

// The last few palm poses of a hand, for the velocity a released object is thrown with; under Wrap also a body's
// poses (BodyState::path), for the let-go's measure of its motion.
// Velocities are least-squares slopes over the samples of the last `span` seconds (GraspSettings::velocity_window_s;
// 0: all kept): exact for constant linear and angular velocity, and a single jittery sample moves them less than a
// two-sample difference would. Rotation between the oldest and newest sample used must stay below pi (over 0.05 s:
// |omega| < 60 rad/s).
class HandMotionHistory {
 public:
  // window >= 2 samples kept; span >= 0 s.
  explicit HandMotionHistory(int window = GraspSettings{}.velocity_window,
                             double span = GraspSettings{}.velocity_window_s);

  // Times must be finite and strictly increasing; poses finite with unit quaternions. Throws handsim::Error.
  void push(const Pose& palm, double time);
  void clear();
  int size() const { return count_; }
  int window() const { return static_cast<int>(samples_.size()); }
  bool has_velocity() const { return count_ >= 2; }  // below that, the velocities are zero
  double newest_time() const { return count_ > 0 ? sample(0).time : 0.0; }  // 0 when empty

  // Both are slopes over the samples of the last `span` seconds, evaluated at the first read after a push and
  // kept until the next (the step asks for them per pair and per held body, and most pushes are never read: a
  // body's path is read at a let-go only).
  Vec3 linear_velocity() const { return slopes().first; }    // of the palm position (m/s)
  Vec3 angular_velocity() const { return slopes().second; }  // world frame (rad/s)
  // Velocity of a point rigidly attached to the palm, at its current world position x: v + w x (x - palm),
  // with palm the latest palm position. This is what an object released from the hand should get.
  Vec3 point_velocity(const Vec3& world_point) const;
  // linear = point_velocity(centre_of_mass), angular = angular_velocity().
  BodyVelocity attached_body_velocity(const Vec3& centre_of_mass) const;

  bool in_time_order() const;  // strictly increasing times, as push keeps them (a restored state is checked)

  // The ring buffer as it is (its length is the world's velocity_window), for save, restore and the hash.
  template <class Visitor, class Self>
  static void visit_state(Self& h, Visitor& v) {
    v.fixed_list(h.samples_, [&v](auto& s) {
      v.state(s.pose);
      v.state(s.time);
    });
    v.index(h.next_, uint32_t(h.samples_.size()));
    v.index(h.count_, uint32_t(h.samples_.size() + 1));
    // The velocities are a function of the samples: made again when read after a restore wrote them, never saved.
    if constexpr (!std::is_const_v<Self>) h.stale_ = true;
  }

 private:
  struct Sample {
    Pose pose;
    double time = 0;
  };
  const Sample& sample(int age) const;  // 0 = newest
  // linear_, angular_ from the samples of the span (both least-squares slopes), when the samples changed since.
  const std::pair<Vec3, Vec3>& slopes() const;
  int samples_in_span() const;  // how many of the newest samples the slopes use

  std::vector<Sample> samples_;  // ring buffer
  double span_ = 0;              // s (0: every sample held)
  int next_ = 0;
  int count_ = 0;
  // The slopes of the samples now held, unless stale_ (a cache: the samples decide them; a World reads them
  // under its lock).
  mutable std::pair<Vec3, Vec3> slopes_{Vec3::Zero(), Vec3::Zero()};
  mutable bool stale_ = false;
};

}  // namespace handsim
