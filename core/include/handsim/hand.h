// Hand input (the OpenXR hand skeleton) and the settings of a virtual hand.
#pragma once

#include "handsim/types.h"

#include <array>
#include <cstdint>
#include <vector>

namespace handsim {

enum class Handedness : int { Left = 0, Right = 1 };

// OpenXR XR_EXT_hand_tracking joint order. The thumb has no intermediate joint.
enum HandJoint : int {
  kPalm = 0, kWrist = 1,
  kThumbMetacarpal = 2, kThumbProximal = 3, kThumbDistal = 4, kThumbTip = 5,
  kIndexMetacarpal = 6, kIndexProximal = 7, kIndexIntermediate = 8, kIndexDistal = 9, kIndexTip = 10,
  kMiddleMetacarpal = 11, kMiddleProximal = 12, kMiddleIntermediate = 13, kMiddleDistal = 14, kMiddleTip = 15,
  kRingMetacarpal = 16, kRingProximal = 17, kRingIntermediate = 18, kRingDistal = 19, kRingTip = 20,
  kLittleMetacarpal = 21, kLittleProximal = 22, kLittleIntermediate = 23, kLittleDistal = 24, kLittleTip = 25,
};
constexpr int kHandJointCount = 26;

// One tracked joint. Orientation follows OpenXR: -Z points along the bone towards the fingertip,
// +Y points out of the back of the hand.
struct JointPose {
  Vec3 position = Vec3::Zero();
  Quat orientation = Quat::Identity();
  double radius = 0.01;
  bool valid = true;
};

// One frame of one tracked hand.
struct HandFrame {
  Handedness handedness = Handedness::Right;
  std::array<JointPose, kHandJointCount> joints{};

  // A frame drives the hand only when its palm and wrist are valid; otherwise the hand counts as
  // untracked for this frame (tracking loss), which is legal input.
  bool tracked() const { return joints[kPalm].valid && joints[kWrist].valid; }
  Pose palm_pose() const { return {joints[kPalm].position, joints[kPalm].orientation}; }
};

enum class ParticleSampling : int {
  Random = 0,  // the paper: seeded uniform choice among the mesh vertices
  Even = 1,    // farthest-point sampling: even coverage, smaller largest gap
};

struct HandDef {
  Handedness handedness = Handedness::Right;
  int particle_count = 1182;                 // the paper's number; clamped to the mesh's vertex count
  ParticleSampling sampling = ParticleSampling::Random;
  uint64_t seed = 1;
  double particle_radius = 0.0;              // 0: derived from the particle spacing
  int render_vertices = 39000;               // resolution of the default procedural mesh (approximate)
};

}  // namespace handsim
