#include "deformation.h"

#include "validate.h"

#include <algorithm>

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
  std::vector<double> wsum(model.vertex_count(), 0.0);
  Eigen::Matrix3Xd acc = Eigen::Matrix3Xd::Zero(3, model.vertex_count());
  for (int p : state.displaced) {
    Vec3 d = state.deformed_positions.col(p) - state.tracked_positions.col(p);
    for (int e = model.falloff_begin[p]; e < model.falloff_begin[p + 1]; ++e) {
      acc.col(model.falloff_vertex[e]) += model.falloff_weight[e] * d;
      wsum[model.falloff_vertex[e]] += model.falloff_weight[e];
    }
  }
  for (int v = 0; v < model.vertex_count(); ++v)
    if (wsum[v] > 0) out.col(v) += acc.col(v) / wsum[v];
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
