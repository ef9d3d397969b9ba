// Contact helpers the world needs beyond collide_particles (hand.h): internal, not part of the public API.
#pragma once

#include "handsim/hand.h"
#include "pose_fit.h"

#include <utility>
#include <vector>

namespace handsim {

// collide_particles over the centres with index in one of the ascending, disjoint ranges [first, second).
// Contacts come out in particle order, so skipping particles that cannot touch leaves the result unchanged.
void collide_particle_ranges(const Eigen::Matrix3Xd& centres, const std::vector<std::pair<int, int>>& ranges,
                             double radius, const PreparedShape& shape, const Pose& body_pose,
                             std::vector<ParticleContact>& out);

// The face through which a point now at body-local `l`, inside the shape, came in while moving with
// body-local velocity `u` relative to the body: the first face the ray l - t u (t > 0) leaves through, as
// a plane normal . x = offset (normal outward, unit). Boxes and convex hulls only, the shapes thin enough to
// be crossed past their middle in one frame; false for other shapes or u = 0 (keep the nearest face then),
// and false when that face lies further back than `max_time` along u: the velocity then does not explain how
// the point got in (the body moved onto a still hand; a noisy estimate), and the far face it names would
// ask for a push of centimetres. `normal` and `offset` are left untouched unless it returns true.
// The world-axis box around a body-local box [llo, lhi] at `pose` (one place for the arithmetic of
// shape_world_bounds, the broadphase boxes and the static stop, which start from a prepared shape's cached bounds).
void local_box_in_world(const Vec3& llo, const Vec3& lhi, const Pose& pose, Vec3& lo, Vec3& hi);

bool entry_face(const PreparedShape& ps, const Vec3& l, const Vec3& u, double max_time, Vec3& normal,
                double& offset);

struct HandReach;

// The hold check's test (HandParticles::holds_still): whether every bone that moves particles (reach >= 0) has
// moved at most `limit` relative to a body since `then` (the bones in the body's frame then; Rt and origin: the
// body's world-to-body rotation and its position now). moves[k] gets bone k's move |dR| reach + |dR j + dt| for
// the bones looked at (all of them when it returns true; it stops at the first that moved more). Four bones at a
// time where the CPU has AVX2, with the bits of bones_within_scalar (one bone at a time, and the path elsewhere).
bool bones_within(const Mat3& Rt, const Vec3& origin, const std::array<BoneTransform, kHandJointCount>& bones,
                  const BoneTransform* then, const HandReach& reach, double limit, double* moves);
bool bones_within_scalar(const Mat3& Rt, const Vec3& origin, const std::array<BoneTransform, kHandJointCount>& bones,
                         const BoneTransform* then, const HandReach& reach, double limit, double* moves);

class HandMotionHistory;
class ArticulationHistory;

// How a hand moves at its particles (keep_entry_faces): the palm's rigid motion, or, where the world keeps its
// bones' history (`bones`, keeps_articulation), each particle's own motion on its bone, measured as the Wrap press
// measures it (ArticulationHistory::point_velocity over `span` s, at most `most` samples).
struct HandMotion {
  const HandMotionHistory& palm;
  const ArticulationHistory* bones = nullptr;
  const HandModel* model = nullptr;
  double span = 0;
  int most = 0;
};

// A face plane in body coordinates: points x on it satisfy normal . x = offset; normal points out.
struct EntryFace {
  int particle = -1;
  Vec3 normal = Vec3::UnitY();
  double offset = 0;
  bool crossing = false;  // the centre was inside, or is coming out on the far side (keep_entry_faces)
  double depth = 0;       // the depth the face gave the contact
};

// Contact persistence through thin bodies (contacts.cpp says why): each contact of a particle that entered the
// body through a face keeps that face while its centre is inside, or is coming out on the far side, and is
// measured against it. `contacts` (sorted by particle) are rewritten in place; `faces` gets this step's face
// of each, `previous` is last step's list of the same (hand, body) pair. `body` is the body's velocity and
// `hand` the hand's motion (for the motion relative to the body).
void keep_entry_faces(const Eigen::Matrix3Xd& centres, double radius, const PreparedShape& shape, const Pose& pose,
                      const BodyVelocity& body, const HandMotion& hand, double dt,
                      const std::vector<EntryFace>& previous, std::vector<EntryFace>& faces,
                      std::vector<ParticleContact>& contacts);

}  // namespace handsim
