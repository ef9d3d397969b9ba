// Local deformation (paper Fig. 3b): particles inside an object move back to its surface, and the render
// vertices near them follow with a smooth falloff.
#pragma once

#include "handsim/hand.h"

namespace handsim {

// Fills model.falloff_*: each render vertex takes normalized weights over its (up to) 4 nearest particles
// within model.falloff_radius (bind pose), w = (1 - (d/R)^2)^2 / (d^2 + (0.1 R)^2). The 1/d^2 factor makes a
// vertex at a particle follow that particle; the compact kernel keeps a press local; normalization keeps a
// uniform push uniform. Vertices with no particle within R never move.
void build_falloff(HandModel& model);

// deform_particles without the full matrix: the displaced particles (sorted) and their deformed centres,
// with the same arithmetic (so the same bits) as deform_particles gives them. `scratch`, when given, is
// working space kept by the caller (the step reuses it instead of allocating).
void displace_particles(const HandModel& model, const Eigen::Matrix3Xd& tracked,
                        const std::vector<ParticleContact>& contacts, std::vector<int>& displaced,
                        std::vector<Vec3>& centres, std::vector<std::pair<int, int>>* scratch = nullptr);

// out.col(v) += sum over displaced particles p of w_vp * (deformed_p - tracked_p).
void apply_render_deformation(const HandModel& model, const HandState& state, Eigen::Matrix3Xd& out);

}  // namespace handsim
