// Choosing the physics particles among the mesh vertices, and measuring how well they cover the skin.
#pragma once

#include "handsim/hand.h"

#include <cstdint>
#include <vector>

namespace handsim {

// `count` distinct vertex indices among those with candidate[i] != 0, ascending.
//  Random: seeded uniform choice without replacement (partial Fisher-Yates on a mt19937_64 stream; the modulo
//    reduction is used instead of std::uniform_int_distribution so the choice is the same on every platform).
//  Even: farthest-point sampling from a seeded random start: each new particle is the candidate farthest from
//    all chosen so far.
std::vector<int> sample_particles(const Eigen::Matrix3Xd& positions, const std::vector<uint8_t>& candidate,
                                  int count, ParticleSampling sampling, uint64_t seed);

// Max over the candidate vertices of the distance to the nearest chosen vertex.
double largest_gap(const Eigen::Matrix3Xd& positions, const std::vector<uint8_t>& candidate,
                   const std::vector<int>& chosen);

// Area of the triangles whose three vertices are candidates (the exposed skin).
double candidate_area(const SkinnedMesh& mesh, const std::vector<uint8_t>& candidate);

}  // namespace handsim
