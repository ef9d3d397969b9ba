// The closed-form particle narrow phase over a subset of the particles (the world's prefilter).
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

}  // namespace handsim
