// Scene builders shared by tests, samples, benchmarks, experiments and the native hosts, so that every one
// of them runs exactly the same scene.
#pragma once

#include "handsim/world.h"

namespace handsim {

// The paper's jewelry box (Sec. IV) on a table. The paper gives no sizes; these are those of a common
// jewelry box: base 18 x 7 x 12 cm (W x H x D), a 1.5 cm lid of the same footprint hinged on the base's
// back top edge, its front lip 1.5 cm past the base, limits 0..90 deg. The user stands at +Z looking along -Z (OpenXR), so the front of the box
// faces +Z and the hinge axis is -X: a positive angle lifts the lid's front edge.
struct JewelryBoxDef {
  Vec3 position = Vec3(0, 0.75, -0.35);  // centre of the base's bottom face (on the table top)
  double yaw = 0;                        // rotation about +Y (rad)
  Vec3 base_half_extents = Vec3(0.09, 0.035, 0.06);
  double lid_half_thickness = 0.0075;
  double lid_overhang = 0.015; // the lid reaches this far past the base's front face: a lip to lift it by
  double base_mass = 0.5;  // kg; 0 fixes the base to the table
  double lid_mass = 0.15;
  double lower = 0;
  double upper = 0.5 * M_PI;
  double damping = 0.002;  // N m s/rad: a little hinge friction
  double friction = 0.6;
  bool table = true;  // a static table (1.2 x 0.75 x 0.8 m) under the box; its top is at position.y
  JointModel model = JointModel::Hard;
  JointSolver solver = JointSolver::Exact;
};

struct JewelryBox {
  BodyId table;  // null without a table
  BodyId base;
  BodyId lid;
  JointId hinge;
  JewelryBoxDef def;

  // World points for scripted hands: the middle of the lid's front edge (at the current lid angle), and
  // the hinge pivot.
  Vec3 lid_front(const World& world) const;
  Vec3 hinge_pivot(const World& world) const;
  Vec3 hinge_axis(const World& world) const;  // unit, world

  // Scripted hands. The palm pose of a right hand (palm down, fingers towards the hinge) pinching the closed
  // lid's front lip with make_hand_frame's kLidPinch shape: index and middle pads on the lid, thumb under the
  // lip; `lift` raises it by that much (m) and `angle` swings it about the hinge axis as if the lid were
  // open by that angle. A left hand mirrors it.
  Pose lid_pinch_palm(const World& world, Handedness handedness, double angle, double lift = 0) const;
};

// The hand shape lid_pinch_palm is made for: thumb half opposed, fingers straight.
HandPoseParams lid_pinch_shape();

// The scripted two-hand jewelry-box scenario that determinism tests and every driver (C++, Python, C, C#)
// replay: frame i (60 Hz) of a world built with build_jewelry_box(world) and, in this order, a right and a
// left hand (HandDef defaults). The right hand arrives open at the lid's lip and closes its pinch there
// (closing_grip), swings the lid open to 80 deg and back; the left hand rests on the base's side, then leaves. kScenarioFrames frames make one run.
constexpr int kScenarioFrames = 1000;
std::vector<HandFrame> scenario_frames(const JewelryBox& box, const World& world, int frame);

// Adds the table (optional), the base, the lid and the hinge to `world`. Throws Error naming the field
// ("jewelry_box.lid_mass") on bad input; the world is unchanged then.
JewelryBox build_jewelry_box(World& world, const JewelryBoxDef& def = {});

}  // namespace handsim
