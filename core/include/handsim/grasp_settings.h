// Settings of the grasp decision (eq. 3), its hysteresis, release and tracking grace.
#pragma once

#include "handsim/types.h"

namespace handsim {

// Eq. 3 as printed reads "d_i^T d_i < gamma, gamma = 0.7" (the second index is garbled). Our reading: an object
// is grasped when two penetration directions point against each other, d_i . d_j < -0.7 (more than ~134
// degrees apart: thumb and finger pinching from opposite sides). The literal "< +0.7" (more than ~46 degrees
// apart) stays selectable, e.g. to compare with the paper.
constexpr double kOpposingCos = -0.7;
constexpr double kPaperLiteralCos = 0.7;

// Defaults assume a 60 Hz tracker (~30-90 Hz are common); the world issue is to measure them on recordings.
struct GraspSettings {
  double cos_threshold = kOpposingCos;  // c of opposing_contacts (see kPaperLiteralCos)
  // 2 frames (33 ms at 60 Hz): a single frame of tracking jitter that pushes two particles into opposite
  // faces must not grab the object, while the added latency stays below what users notice (~50 ms).
  int frames_to_grasp = 2;
  // 3 frames (50 ms): contacts of a held object flicker for a frame or two as the fingers jitter on its
  // surface; releasing needs them gone for longer than that. Slightly longer than grasping because a false
  // drop is worse than a late grab.
  int frames_to_release = 3;
  // Not used by GraspTracker: the world's contact query for a *grasped* object should count particles within
  // this distance (m) of its surface as contacts, because an attached object no longer gets penetrated and
  // its contacts would otherwise vanish at once. 5 mm ~ one particle radius of the default hand.
  double release_distance = 0.005;
  // 0.2 s: typical optical-tracking dropouts (occlusion by the other hand, a finger leaving the view) last
  // a few frames; a hand that is really gone is released within a fifth of a second.
  double tracking_grace_s = 0.2;
  // 4 samples (50 ms at 60 Hz) for the throw velocity: a least-squares slope over 4 samples weighs one bad
  // frame 0.3x as much as a two-frame difference does, and lags only ~25 ms.
  int velocity_window = 4;
};
// Throws handsim::Error naming the bad field.
void validate_grasp_settings(const GraspSettings& s);

}  // namespace handsim
