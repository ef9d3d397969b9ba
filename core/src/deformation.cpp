#include "deformation.h"

#include "validate.h"
#include "world_impl.h"

#include <algorithm>
#include <array>
#include <cstdint>
#include <unordered_map>
#include <vector>

namespace handsim {

namespace {

// Particles bucketed in cubes of the falloff radius: the particles within R of a point lie in the 27 cubes
// around it, so building the falloff costs O(vertices) instead of O(vertices x particles), which at 39k
// vertices and 3,000 particles was the larger part of World::add_hand.
class ParticleGrid {
 public:
  ParticleGrid(const Eigen::Matrix3Xd& points, double cell) : cell_(cell) {
    for (int p = 0; p < int(points.cols()); ++p) cells_[key(coord(points.col(p)))].push_back(p);
  }
  template <class F>
  void for_each_near(const Vec3& x, F&& f) const {
    const Eigen::Vector3i c = coord(x);
    for (int dx = -1; dx <= 1; ++dx)
      for (int dy = -1; dy <= 1; ++dy)
        for (int dz = -1; dz <= 1; ++dz) {
          auto it = cells_.find(key(c + Eigen::Vector3i(dx, dy, dz)));
          if (it != cells_.end())
            for (int p : it->second) f(p);
        }
  }

 private:
  Eigen::Vector3i coord(const Vec3& x) const { return (x / cell_).array().floor().cast<int>(); }
  static int64_t key(const Eigen::Vector3i& c) {
    return (int64_t(c.x()) & 0x1fffff) | ((int64_t(c.y()) & 0x1fffff) << 21) | ((int64_t(c.z()) & 0x1fffff) << 42);
  }
  double cell_;
  std::unordered_map<int64_t, std::vector<int>> cells_;
};

}  // namespace

void build_falloff(HandModel& model) {
  const int nv = model.vertex_count(), np = model.particle_count();
  const double R = model.falloff_radius, R2 = R * R, eps2 = 0.01 * R2;
  std::vector<std::vector<std::pair<int, double>>> per_particle(np);
  const ParticleGrid grid(model.particle_bind, R);
  for (int v = 0; v < nv; ++v) {
    const Vec3 x = model.mesh.positions.col(v);
    // The 4 nearest within R, ties by particle index, so the result does not depend on the scan order.
    std::array<std::pair<double, int>, 4> near;
    near.fill({R2, -1});
    grid.for_each_near(x, [&](int p) {
      const std::pair<double, int> candidate{(model.particle_bind.col(p) - x).squaredNorm(), p};
      if (candidate.first >= R2 || !(candidate < near[3])) return;
      near[3] = candidate;
      std::sort(near.begin(), near.end());  // 4 elements: insertion into a sorted tiny array
    });
    double sum = 0;
    std::array<double, 4> w{};
    for (int k = 0; k < 4; ++k) {
      if (near[k].second < 0) continue;
      const double f = 1 - near[k].first / R2;
      w[k] = f * f / (near[k].first + eps2);
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

void displace_particles(const HandModel& model, const Eigen::Matrix3Xd& tracked,
                        const std::vector<ParticleContact>& contacts, std::vector<int>& displaced,
                        std::vector<Vec3>& centres, std::vector<std::pair<int, int>>* scratch) {
  const double r = model.particle_radius;
  // (particle, contact) for every contact whose centre is inside, stably by particle: each particle then adds
  // its corrections in contact order, as deform_particles does in its pass over the contacts.
  std::vector<std::pair<int, int>> local;
  std::vector<std::pair<int, int>>& inside = scratch ? *scratch : local;
  inside.clear();
  for (size_t c = 0; c < contacts.size(); ++c)
    if (contacts[c].depth > r) inside.push_back({contacts[c].particle, int(c)});
  auto by_particle = [](const std::pair<int, int>& a, const std::pair<int, int>& b) { return a.first < b.first; };
  // One hand on one body gives them sorted already (contacts come sorted by particle): no sort, no buffer.
  if (!std::is_sorted(inside.begin(), inside.end(), by_particle))
    std::stable_sort(inside.begin(), inside.end(), by_particle);
  displaced.clear();
  centres.clear();
  for (size_t i = 0; i < inside.size();) {
    const int p = inside[i].first;
    if (p < 0 || p >= tracked.cols())
      validate::fail("contacts[" + std::to_string(inside[i].second) + "].particle", "out of range: " + std::to_string(p));
    Vec3 x = tracked.col(p);
    for (; i < inside.size() && inside[i].first == p; ++i) x += contacts[inside[i].second].point - tracked.col(p);
    displaced.push_back(p);
    centres.push_back(x);
  }
}

// --- local deformation: penetrating particles move back to the surface (what the user sees) ---
StageReport deform_hands(HandParticles& particles) {
  int deformed = 0;
  for (uint32_t hi = 0; hi < particles.hands.size(); ++hi)
    if (particles.hands[hi].alive && particles.hands[hi].state.tracked) deformed += particles.deform_hand(hi);
  if (deformed == 0) return stage_skipped(SkipReason::NoParticleInside);
  return stage_work(deformed, deformed);
}

// One hand's deformation from its contacts of the frame (with a lazy pair's witnesses only until
// complete_contacts redoes it); returns how many particles it displaced.
int HandParticles::deform_hand(uint32_t hi) {
  HandSlot& h = hands[hi];
  std::vector<ParticleContact>& all = scratch.contacts;
  all.clear();
  for (auto it = pairs.lower_bound({hi, 0}); it != pairs.end() && it->first.first == hi; ++it)
    for (const ParticleContact& c : it->second.contacts)
      if (c.depth > 0) all.push_back(c);
  if (all.empty() && !def.paper_pipeline) {
    h.state.displaced.clear();  // deformed == tracked; the copy is made only if someone reads it
    h.deformed_current = false;
    return 0;
  }
  if (def.paper_pipeline) {
    refresh_particles(h, false);
    deform_particles(*h.model, h.state, all);
    h.deformed_current = true;
  } else {
    // Only the touching particles: their deformed centres are kept aside and the full deformed matrix is
    // made when read (refresh_particles), so 3 touching particles of 10,000 cost 3, not a 10,000 copy.
    displace_particles(*h.model, h.state.tracked_positions, all, h.state.displaced, h.displaced_centres,
                       &scratch.inside);
    h.deformed_current = false;
  }
  return int(h.state.displaced.size());
}

}  // namespace handsim
