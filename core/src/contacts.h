// Contact helpers the world needs beyond collide_particles (hand.h): internal, not part of the public API.
#pragma once

#include "handsim/hand.h"

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
// ask for a push of centimetres.
bool entry_face(const PreparedShape& ps, const Vec3& l, const Vec3& u, double max_time, Vec3& normal,
                double& offset);

}  // namespace handsim
