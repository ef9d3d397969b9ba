#include "deformation.h"

#include "validate.h"

#include <algorithm>
#include <vector>

namespace handsim {

void build_falloff(HandModel& model) {
  const int nv = model.vertex_count(), np = model.particle_count();
  const double R = model.falloff_radius, R2 = R * R, eps2 = 0.01 * R2;
  std::vector<std::vector<std::pair<int, double>>> per_particle(np);
  Eigen::RowVectorXd d2;
  for (int v = 0; v < nv; ++v) {
    d2 = (model.particle_bind.colwise() - model.mesh.positions.col(v)).colwise().squaredNorm();
    std::array<std::pair<double, int>, 4> near;
    near.fill({R2, -1});
    for (int p = 0; p < np; ++p) {
      if (d2[p] >= near[3].first) continue;
      near[3] = {d2[p], p};
      std::sort(near.begin(), near.end());  // 4 elements: insertion into a sorted tiny array
    }
    double sum = 0;
    std::array<double, 4> w{};
    for (int k = 0; k < 4; ++k) {
      if (near[k].second < 0) continue;
      double x = 1 - near[k].first / R2;
      w[k] = x * x / (near[k].first + eps2);
      sum += w[k];
    }
    if (sum <= 0) continue;
    for (int k = 0; k < 4; ++k)
      if (near[k].second >= 0) per_particle[near[k].second].push_back({v, w[k] / sum});
  }
  model.falloff_begin.assign(np + 1, 0);
  model.falloff_vertex.clear();
  model.falloff_weight.clear();
  for (int p = 0; p < np; ++p) {
    for (auto& e : per_particle[p]) {
      model.falloff_vertex.push_back(e.first);
      model.falloff_weight.push_back(e.second);
    }
    model.falloff_begin[p + 1] = int(model.falloff_vertex.size());
  }
}

void apply_render_deformation(const HandModel& model, const HandState& state, Eigen::Matrix3Xd& out) {
  if (state.displaced.empty()) return;
  // Normalized over the displaced neighbours only: an undisplaced neighbour sits outside the object, so
  // averaging it in would pull a pressed vertex back inside. The displacement stays continuous because a
  // particle that barely penetrates is barely displaced.
  // Sparse: only the falloff entries of displaced particles are visited (no per-vertex arrays to clear). The
  // entries are stably sorted by vertex, so each vertex sums its terms in the order of the displaced list.
  struct Term {
    int vertex, particle, entry;
  };
  std::vector<Term> terms;
  for (size_t k = 0; k < state.displaced.size(); ++k) {
    const int p = state.displaced[k];
    for (int e = model.falloff_begin[p]; e < model.falloff_begin[p + 1]; ++e)
      terms.push_back({model.falloff_vertex[e], p, e});
  }
  std::stable_sort(terms.begin(), terms.end(), [](const Term& a, const Term& b) { return a.vertex < b.vertex; });
  for (size_t i = 0; i < terms.size();) {
    const int v = terms[i].vertex;
    Vec3 acc = Vec3::Zero();
    double wsum = 0;
    for (; i < terms.size() && terms[i].vertex == v; ++i) {
      const int p = terms[i].particle;
      const double w = model.falloff_weight[terms[i].entry];
      acc += w * (state.deformed_positions.col(p) - state.tracked_positions.col(p));
      wsum += w;
    }
    if (wsum > 0) out.col(v) += acc / wsum;
  }
}

void deform_particles(const HandModel& model, HandState& state, const std::vector<ParticleContact>& contacts) {
  const int n = model.particle_count();
  if (state.tracked_positions.cols() != n)
    validate::fail("state", "was not posed with this model (pose_hand first)", Status::InvalidState);
  state.deformed_positions = state.tracked_positions;
  state.displaced.clear();
  const double r = model.particle_radius;
  for (size_t c = 0; c < contacts.size(); ++c) {
    const ParticleContact& k = contacts[c];
    if (k.particle < 0 || k.particle >= n)
      validate::fail("contacts[" + std::to_string(c) + "].particle", "out of range: " + std::to_string(k.particle));
    // The centre is inside when its signed distance r - depth is negative; it moves to the surface point.
    if (k.depth <= r) continue;
    state.deformed_positions.col(k.particle) += k.point - state.tracked_positions.col(k.particle);
    state.displaced.push_back(k.particle);
  }
  std::sort(state.displaced.begin(), state.displaced.end());
  state.displaced.erase(std::unique(state.displaced.begin(), state.displaced.end()), state.displaced.end());
}

}  // namespace handsim
