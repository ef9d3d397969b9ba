#include "particles.h"

#include <algorithm>
#include <limits>
#include <random>

namespace handsim {

std::vector<int> sample_particles(const Eigen::Matrix3Xd& positions, const std::vector<uint8_t>& candidate,
                                  int count, ParticleSampling sampling, uint64_t seed) {
  std::vector<int> pool;
  for (int i = 0; i < int(candidate.size()); ++i)
    if (candidate[i]) pool.push_back(i);
  count = std::min<int>(count, int(pool.size()));
  std::mt19937_64 rng(seed);
  std::vector<int> chosen;
  if (sampling == ParticleSampling::Random) {
    for (int i = 0; i < count; ++i) {
      size_t j = i + size_t(rng() % uint64_t(pool.size() - i));
      std::swap(pool[i], pool[j]);
    }
    chosen.assign(pool.begin(), pool.begin() + count);
  } else {
    // Farthest-point sampling: O(count * candidates), done once per model (every World::add_hand samples
    // afresh). The candidates' coordinates are copied into contiguous arrays so that the distance update
    // vectorizes; the first farthest candidate wins a tie, as in a plain scan.
    const Eigen::Index n = Eigen::Index(pool.size());
    Eigen::ArrayXd px(n), py(n), pz(n);
    for (Eigen::Index i = 0; i < n; ++i) {
      px[i] = positions(0, pool[i]);
      py[i] = positions(1, pool[i]);
      pz[i] = positions(2, pool[i]);
    }
    Eigen::ArrayXd d2 = Eigen::ArrayXd::Constant(n, std::numeric_limits<double>::infinity());
    Eigen::Index next = count > 0 ? Eigen::Index(rng() % uint64_t(n)) : 0;
    for (int c = 0; c < count; ++c) {
      chosen.push_back(pool[next]);
      d2 = d2.min((px - px[next]).square() + (py - py[next]).square() + (pz - pz[next]).square());
      d2.maxCoeff(&next);
    }
  }
  std::sort(chosen.begin(), chosen.end());  // memory order for the per-frame skinning
  return chosen;
}

double largest_gap(const Eigen::Matrix3Xd& positions, const std::vector<uint8_t>& candidate,
                   const std::vector<int>& chosen) {
  if (chosen.empty()) return std::numeric_limits<double>::infinity();
  Eigen::Matrix3Xd c(3, chosen.size());
  for (size_t k = 0; k < chosen.size(); ++k) c.col(k) = positions.col(chosen[k]);
  double worst = 0;
  for (int i = 0; i < int(candidate.size()); ++i) {
    if (!candidate[i]) continue;
    double best = (c.colwise() - positions.col(i)).colwise().squaredNorm().minCoeff();
    worst = std::max(worst, best);
  }
  return std::sqrt(worst);
}

double candidate_area(const SkinnedMesh& mesh, const std::vector<uint8_t>& candidate) {
  double area = 0;
  for (size_t t = 0; t + 2 < mesh.triangles.size(); t += 3) {
    int a = mesh.triangles[t], b = mesh.triangles[t + 1], c = mesh.triangles[t + 2];
    if (!candidate[a] || !candidate[b] || !candidate[c]) continue;
    Vec3 pa = mesh.positions.col(a), pb = mesh.positions.col(b), pc = mesh.positions.col(c);
    area += 0.5 * (pb - pa).cross(pc - pa).norm();
  }
  return area;
}

}  // namespace handsim
