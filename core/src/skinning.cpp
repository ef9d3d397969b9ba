#include "skinning.h"

#include "deformation.h"
#include "simd4.h"
#include "world_impl.h"

#include <algorithm>
#include <limits>
#include <map>
#include <thread>

// Runtime dispatch of the skinning loop: GCC compiles it for AVX2 and for the baseline and picks one at load
// time, so the portable binary uses 4-wide vectors where the CPU has them. Both clones do the same IEEE
// multiplies and adds (FMA is not enabled and contraction is off), so they give the same bits.
// Not under ThreadSanitizer: the clones' ifunc resolver runs during relocation, before TSan's runtime is up,
// and its instrumented code crashes the program at load (seen with GCC 12).
#if defined(HANDSIM_SIMD_DISPATCH) && defined(__x86_64__) && defined(__GNUC__) && !defined(__clang__) && \
    defined(__linux__) && !defined(__SANITIZE_THREAD__)
#define HANDSIM_SIMD_CLONES __attribute__((target_clones("avx2", "default")))
#define HANDSIM_INLINE inline __attribute__((always_inline))
#else
#define HANDSIM_SIMD_CLONES
#define HANDSIM_INLINE inline
#endif

namespace handsim {
namespace {

// The joint whose bone leads to joint j: the previous joint in the chain, the wrist for metacarpals.
int parent_of(int j) {
  if (j == kPalm) return kWrist;
  if (j == kWrist) return -1;
  if (j == kThumbMetacarpal || j == kIndexMetacarpal || j == kMiddleMetacarpal || j == kRingMetacarpal ||
      j == kLittleMetacarpal)
    return kWrist;
  return j - 1;
}

BoneTransform to_matrix(const Pose& p) {
  BoneTransform m;
  m.leftCols<3>() = p.orientation.toRotationMatrix();
  m.col(3) = p.position;
  return m;
}

// B_j = pose_j * bind_j^-1, the definition (and the kernel's reference: tests/cpp/test_hand_skinning.cpp).
BoneTransform bone_of(const HandModel& model, const JointPose& jp, int j) {
  return to_matrix(Pose{jp.position, jp.orientation.normalized()} * model.bind_inverse[j]);
}

#ifdef HANDSIM_AVX2_KERNELS
using simd4::V4;
// A 4-double load at a Vec3 reads the padding before the quaternion that follows it (lane 3: unused).
static_assert(sizeof(Vec3) == 24 && alignof(Quat) >= 16, "a Vec3 followed by a Quat leaves 8 bytes of padding");

// bone_of for the joints j[0..3] at once, lane k for j[k]: Eigen's arithmetic in Eigen's order, so each lane's
// bits are bone_of's -- normalized() as coeffs / sqrt((x x + z z) + (y y + w w)) (its SSE2 sum), the position as
// q * v (uv = 2 q.vec x v, v + w uv + q.vec x uv) + p, the product as Eigen's SSE2 quat_product, then
// toRotationMatrix. The joints' numbers are loaded as rows and transposed into lanes, the bones back.
HANDSIM_AVX2 void bone_block(const HandModel& model, const HandFrame& frame, const int* j, BoneTransform* const* out) {
  using simd4::load;
  using simd4::transpose;
  const auto& J = frame.joints;
  const auto& B = model.bind_inverse;
  V4 x = load(J[j[0]].orientation.coeffs().data()), y = load(J[j[1]].orientation.coeffs().data()),
     z = load(J[j[2]].orientation.coeffs().data()), w = load(J[j[3]].orientation.coeffs().data());
  transpose(x, y, z, w);
  V4 px = load(J[j[0]].position.data()), py = load(J[j[1]].position.data()), pz = load(J[j[2]].position.data()),
     unused = load(J[j[3]].position.data());
  transpose(px, py, pz, unused);
  V4 bx = load(B[j[0]].orientation.coeffs().data()), by = load(B[j[1]].orientation.coeffs().data()),
     bz = load(B[j[2]].orientation.coeffs().data()), bw = load(B[j[3]].orientation.coeffs().data());
  transpose(bx, by, bz, bw);
  V4 vx = load(B[j[0]].position.data()), vy = load(B[j[1]].position.data()), vz = load(B[j[2]].position.data());
  unused = load(B[j[3]].position.data());
  transpose(vx, vy, vz, unused);
  V4 n = simd4::sqrt((x * x + z * z) + (y * y + w * w));
  x /= n, y /= n, z /= n, w /= n;
  V4 ux = y * vz - z * vy, uy = z * vx - x * vz, uz = x * vy - y * vx;
  ux += ux, uy += uy, uz += uz;
  V4 m[12];  // column-major 3x4, as BoneTransform
  m[9] = ((vx + w * ux) + (y * uz - z * uy)) + px;
  m[10] = ((vy + w * uy) + (z * ux - x * uz)) + py;
  m[11] = ((vz + w * uz) + (x * uy - y * ux)) + pz;
  V4 qx = (w * bx + y * bz) - (z * by - x * bw), qy = (w * by + y * bw) + (z * bx - x * bz);
  V4 qz = (w * bz - y * bx) + (z * bw + x * by), qw = (w * bw - y * by) - (z * bz + x * bx);
  n = simd4::sqrt((qx * qx + qz * qz) + (qy * qy + qw * qw));
  qx /= n, qy /= n, qz /= n, qw /= n;
  const V4 tx = 2 * qx, ty = 2 * qy, tz = 2 * qz, twx = tx * qw, twy = ty * qw, twz = tz * qw, txx = tx * qx,
           txy = ty * qx, txz = tz * qx, tyy = ty * qy, tyz = tz * qy, tzz = tz * qz;
  m[0] = 1 - (tyy + tzz), m[3] = txy - twz, m[6] = txz + twy;
  m[1] = txy + twz, m[4] = 1 - (txx + tzz), m[7] = tyz - twx;
  m[2] = txz - twy, m[5] = tyz + twx, m[8] = 1 - (txx + tyy);
  transpose(m[0], m[1], m[2], m[3]);
  transpose(m[4], m[5], m[6], m[7]);
  transpose(m[8], m[9], m[10], m[11]);
  for (int k = 0; k < 4; ++k)
    for (int c = 0; c < 3; ++c) simd4::store(out[k]->data() + 4 * c, m[4 * c + k]);
}

// Every joint's bone_of, valid or not (an invalid joint's is replaced after).
__attribute__((target("avx2"))) void all_bones_avx2(const HandModel& model, const HandFrame& frame,
                                                    std::array<BoneTransform, kHandJointCount>& bones) {
  static_assert(kHandJointCount == 26, "six blocks of four and one of two");
#pragma GCC unroll 8
  for (int b = 0; b < 24; b += 4) {
    const int j[4] = {b, b + 1, b + 2, b + 3};
    BoneTransform* const out[4] = {&bones[b], &bones[b + 1], &bones[b + 2], &bones[b + 3]};
    bone_block(model, frame, j, out);
  }
  BoneTransform spare[2];
  const int j[4] = {24, 25, 25, 25};
  BoneTransform* const out[4] = {&bones[24], &bones[25], &spare[0], &spare[1]};
  bone_block(model, frame, j, out);
}
#endif

}  // namespace

namespace {
// An invalid joint is rigidly attached to its parent: pose_j = pose_p * bind_p^-1 * bind_j, so B_j = B_p.
// Parents come before children but for the palm, whose parent (the wrist) is valid in a tracked frame as it is.
// Unrolled, so each joint's parent is a constant and a tracked frame (every joint valid) costs a test per joint.
void follow_parents(const HandFrame& frame, std::array<BoneTransform, kHandJointCount>& bones) {
#pragma GCC unroll 26
  for (int j = 0; j < kHandJointCount; ++j)
    if (!frame.joints[j].valid) bones[j] = bones[parent_of(j)];
}
}  // namespace

void compute_bone_transforms(const HandModel& model, const HandFrame& frame,
                             std::array<BoneTransform, kHandJointCount>& bones) {
#ifdef HANDSIM_AVX2_KERNELS
  if (simd4::has_avx2()) {
    all_bones_avx2(model, frame, bones);
    follow_parents(frame, bones);
    return;
  }
#endif
  compute_bone_transforms_scalar(model, frame, bones);
}

void compute_bone_transforms_scalar(const HandModel& model, const HandFrame& frame,
                                    std::array<BoneTransform, kHandJointCount>& bones) {
  for (int j = 0; j < kHandJointCount; ++j)
    if (frame.joints[j].valid) bones[j] = bone_of(model, frame.joints[j], j);
  follow_parents(frame, bones);
}

void skin_points(const Eigen::Matrix3Xd& bind, const Eigen::Matrix<int, 4, Eigen::Dynamic>& bone_ids,
                 const Eigen::Matrix4Xd& weights, const std::array<BoneTransform, kHandJointCount>& bones,
                 Eigen::Matrix3Xd& out) {
  const Eigen::Index n = bind.cols();
  out.resize(3, n);
  for (Eigen::Index i = 0; i < n; ++i) {
    Eigen::Vector4d h(bind(0, i), bind(1, i), bind(2, i), 1.0);
    Vec3 v = Vec3::Zero();
    for (int k = 0; k < 4; ++k) {
      double w = weights(k, i);
      if (w != 0) v += w * (bones[bone_ids(k, i)] * h);
    }
    out.col(i) = v;
  }
}

std::vector<int> build_skin_groups(const SkinnedMesh& mesh, HandModel& model) {
  const int n = int(mesh.positions.cols());
  // Key: the vertex's bones with non-zero weight, ascending.
  std::vector<std::array<int, 4>> key(n);
  std::vector<std::array<double, 4>> w(n);
  std::vector<int> count(n);
  for (int i = 0; i < n; ++i) {
    std::array<std::pair<int, double>, 4> inf;
    int c = 0;
    for (int k = 0; k < 4; ++k)
      if (mesh.weights(k, i) > 0) inf[c++] = {mesh.bones(k, i), mesh.weights(k, i)};
    std::sort(inf.begin(), inf.begin() + c);
    // The same bone twice: merge its weights so each group slot is a distinct bone.
    int m = 0;
    for (int k = 0; k < c; ++k) {
      if (m > 0 && inf[m - 1].first == inf[k].first) inf[m - 1].second += inf[k].second;
      else inf[m++] = inf[k];
    }
    key[i].fill(-1);
    w[i].fill(0);
    double sum = 0;
    for (int k = 0; k < m; ++k) sum += inf[k].second;
    for (int k = 0; k < m; ++k) {
      key[i][k] = inf[k].first;
      w[i][k] = inf[k].second / sum;  // validated to be ~1; exact 1 keeps the bind pose exact
    }
    count[i] = m;
  }
  std::vector<int> order(n);
  for (int i = 0; i < n; ++i) order[i] = i;
  std::stable_sort(order.begin(), order.end(), [&](int a, int b) { return key[a] < key[b]; });

  SkinLayout& L = model.skin;
  L.groups.clear();
  for (auto& a : L.bind_xyz) a.resize(n);
  for (auto& a : L.weight) a.assign(n, 0.0);
  for (int i = 0; i < n; ++i) {
    int v = order[i];
    if (L.groups.empty() || key[order[i - 1]] != key[v]) {
      SkinGroup g;
      g.begin = i;
      g.count = std::max(count[v], 1);
      for (int k = 0; k < 4; ++k) g.bones[k] = key[v][k] < 0 ? 0 : key[v][k];
      L.groups.push_back(g);
    }
    L.groups.back().end = i + 1;
    for (int d = 0; d < 3; ++d) L.bind_xyz[d][i] = mesh.positions(d, v);
    for (int k = 0; k < 4; ++k) L.weight[k][i] = w[v][k];
  }
  return order;
}

SkinLayout build_particle_layout(const SkinLayout& render, const std::vector<int>& particle_vertex) {
  const int n = int(particle_vertex.size());
  SkinLayout L;
  for (auto& a : L.bind_xyz) a.resize(n);
  for (auto& a : L.weight) a.resize(n);
  size_t g = 0;  // render group of the current vertex; both sequences ascend
  for (int p = 0; p < n; ++p) {
    const int v = particle_vertex[p];
    while (render.groups[g].end <= v) ++g;
    // A new run at each render group, and every kMaxParticleRun particles: the runs' boxes are the contact
    // prefilter, and short runs of one group keep those boxes tight (the arithmetic is the same either way).
    if (p == 0 || particle_vertex[p - 1] < render.groups[g].begin || p - L.groups.back().begin >= kMaxParticleRun) {
      SkinGroup run = render.groups[g];
      run.begin = p;
      L.groups.push_back(run);
    }
    L.groups.back().end = p + 1;
    for (int d = 0; d < 3; ++d) L.bind_xyz[d][p] = render.bind_xyz[d][v];
    for (int k = 0; k < 4; ++k) L.weight[k][p] = render.weight[k][v];
  }
  return L;
}

namespace {

// Min and max of each coordinate over `count` interleaved xyz points.
HANDSIM_INLINE void group_box(const double* p, int count, double* box) {
  double lo[3] = {p[0], p[1], p[2]}, hi[3] = {p[0], p[1], p[2]};
  for (int i = 1; i < count; ++i)
    for (int d = 0; d < 3; ++d) {
      lo[d] = std::min(lo[d], p[3 * i + d]);
      hi[d] = std::max(hi[d], p[3 * i + d]);
    }
  for (int d = 0; d < 3; ++d) {
    box[d] = lo[d];
    box[3 + d] = hi[d];
  }
}

// One group: N influences with the same bones for every point, so the 12 numbers of each bone are loop
// invariants and the loop body is plain multiply-adds over contiguous arrays (vectorizes).
template <int N>
HANDSIM_INLINE void skin_group(const SkinGroup& g, const SkinLayout& L, const std::array<BoneTransform, kHandJointCount>& bones,
                double* __restrict o, double* box) {
  double b[N][12];
  for (int k = 0; k < N; ++k)
    for (int r = 0; r < 3; ++r)
      for (int c = 0; c < 4; ++c) b[k][4 * r + c] = bones[g.bones[k]](r, c);
  const double* __restrict x = L.bind_xyz[0].data();
  const double* __restrict y = L.bind_xyz[1].data();
  const double* __restrict z = L.bind_xyz[2].data();
  const double* __restrict w[4] = {L.weight[0].data(), L.weight[1].data(), L.weight[2].data(), L.weight[3].data()};
  for (int i = g.begin; i < g.end; ++i) {
    double ox = 0, oy = 0, oz = 0;
    for (int k = 0; k < N; ++k) {
      const double wk = N == 1 ? 1.0 : w[k][i];
      ox += wk * (b[k][0] * x[i] + b[k][1] * y[i] + b[k][2] * z[i] + b[k][3]);
      oy += wk * (b[k][4] * x[i] + b[k][5] * y[i] + b[k][6] * z[i] + b[k][7]);
      oz += wk * (b[k][8] * x[i] + b[k][9] * y[i] + b[k][10] * z[i] + b[k][11]);
    }
    o[3 * i] = ox;
    o[3 * i + 1] = oy;
    o[3 * i + 2] = oz;
  }
  if (box) group_box(o + 3 * g.begin, g.end - g.begin, box);
}

}  // namespace

HANDSIM_SIMD_CLONES
void skin_layout(const SkinLayout& layout, const std::array<BoneTransform, kHandJointCount>& bones, double* out,
                 size_t first, size_t last, double* bounds) {
  for (size_t i = first; i < last; ++i) {
    const SkinGroup& g = layout.groups[i];
    double* box = bounds ? bounds + 6 * i : nullptr;
    switch (g.count) {
      case 1: skin_group<1>(g, layout, bones, out, box); break;
      case 2: skin_group<2>(g, layout, bones, out, box); break;
      case 3: skin_group<3>(g, layout, bones, out, box); break;
      default: skin_group<4>(g, layout, bones, out, box); break;
    }
  }
}

HANDSIM_SIMD_CLONES
void skin_layout_point(const SkinLayout& layout, const std::array<BoneTransform, kHandJointCount>& bones, int i,
                       double* out) {
  // The group holding point i, cut down to it: the same loop body as skin_layout's, so the same bits.
  SkinGroup g = *std::upper_bound(layout.groups.begin(), layout.groups.end(), i,
                                  [](int p, const SkinGroup& group) { return p < group.end; });
  g.begin = i;
  g.end = i + 1;
  switch (g.count) {
    case 1: skin_group<1>(g, layout, bones, out, nullptr); break;
    case 2: skin_group<2>(g, layout, bones, out, nullptr); break;
    case 3: skin_group<3>(g, layout, bones, out, nullptr); break;
    default: skin_group<4>(g, layout, bones, out, nullptr); break;
  }
}

void skin_layout(const SkinLayout& layout, const std::array<BoneTransform, kHandJointCount>& bones,
                 Eigen::Matrix3Xd& out, std::vector<double>* bounds) {
  out.resize(3, Eigen::Index(layout.bind_xyz[0].size()));
  if (bounds) bounds->resize(6 * layout.groups.size());
  skin_layout(layout, bones, out.data(), 0, layout.groups.size(), bounds ? bounds->data() : nullptr);
}

void skin_layout_parallel(const SkinLayout& layout, const std::array<BoneTransform, kHandJointCount>& bones,
                          Eigen::Matrix3Xd& out, int threads) {
  const size_t n = layout.bind_xyz[0].size(), groups = layout.groups.size();
  out.resize(3, Eigen::Index(n));
#ifdef HANDSIM_NO_THREADS
  threads = 1;  // built without threads: the setting is accepted and one thread does the work
#endif
  threads = std::max(1, std::min<int>(threads, int(groups)));
  if (threads == 1) return skin_layout(layout, bones, out.data(), 0, groups);
  // Cut the group list where the running point count passes k * n / threads: equal work per thread.
  std::vector<size_t> cut(threads + 1, groups);
  cut[0] = 0;
  for (size_t g = 0, t = 1; g < groups && t < size_t(threads); ++g)
    if (size_t(layout.groups[g].end) * threads >= t * n) cut[t++] = g + 1;
  std::vector<std::thread> pool;
  for (int t = 1; t < threads; ++t)
    pool.emplace_back([&, t] { skin_layout(layout, bones, out.data(), cut[t], cut[t + 1]); });
  skin_layout(layout, bones, out.data(), cut[0], cut[1]);
  for (std::thread& th : pool) th.join();
}

void skin_groups(const HandModel& model, const std::array<BoneTransform, kHandJointCount>& bones,
                 Eigen::Matrix3Xd& out, int threads) {
  skin_layout_parallel(model.skin, bones, out, threads);
}

void fill_reach_lanes(HandReach& r) {
  for (size_t k = 0; k < r.lanes[0].size(); ++k) {
    const int bone = std::min(int(k), kHandJointCount - 1);
    for (int d = 0; d < 3; ++d) r.lanes[d][k] = r.bind_joint[bone][d];
    r.lanes[3][k] = r.reach[bone] < 0 ? -std::numeric_limits<double>::infinity() : r.reach[bone];
  }
}

HandReach build_hand_reach(const HandModel& model) {
  HandReach r;
  r.reach.fill(-1.0);
  for (int j = 0; j < kHandJointCount; ++j) r.bind_joint[j] = model.bind.joints[j].position;
  const SkinLayout& L = model.particle_skin;
  for (const SkinGroup& g : L.groups) {
    Vec3 lo = Vec3::Constant(std::numeric_limits<double>::infinity()), hi = -lo;
    for (int i = g.begin; i < g.end; ++i) {
      const Vec3 p(L.bind_xyz[0][i], L.bind_xyz[1][i], L.bind_xyz[2][i]);
      lo = lo.cwiseMin(p);
      hi = hi.cwiseMax(p);
      for (int k = 0; k < g.count; ++k) {
        double& reach = r.reach[g.bones[k]];
        reach = std::max(reach, (p - r.bind_joint[g.bones[k]]).norm() + model.particle_radius);
      }
    }
    const Vec3 centre = 0.5 * (lo + hi);
    double radius = 0;
    for (int i = g.begin; i < g.end; ++i)
      radius = std::max(radius, (Vec3(L.bind_xyz[0][i], L.bind_xyz[1][i], L.bind_xyz[2][i]) - centre).norm());
    r.group_centre.push_back(centre);
    r.group_radius.push_back(radius * (1 + 1e-12) + 1e-12);  // rounding of B_k p never leaves the ball
  }
  for (size_t g = 0; g < L.groups.size(); ++g)
    for (int k = 0; k < L.groups[g].count; ++k) {
      const int bone = L.groups[g].bones[k];
      r.group_excess = std::max(r.group_excess, (r.group_centre[g] - r.bind_joint[bone]).norm() + r.group_radius[g] +
                                                    model.particle_radius - r.reach[bone]);
    }
  // Spans: maximal runs of groups with the same bones; a span's ball holds its groups' balls.
  for (size_t g = 0; g < L.groups.size(); ++g) {
    const SkinGroup& a = L.groups[g];
    const bool same = g > 0 && a.count == L.groups[g - 1].count &&
                      std::equal(a.bones.begin(), a.bones.begin() + a.count, L.groups[g - 1].bones.begin());
    if (!same) r.span_first.push_back(g);
  }
  r.span_first.push_back(L.groups.size());
  for (size_t s = 0; s + 1 < r.span_first.size(); ++s) {
    Vec3 lo = Vec3::Constant(std::numeric_limits<double>::infinity()), hi = -lo;
    for (size_t g = r.span_first[s]; g < r.span_first[s + 1]; ++g) {
      lo = lo.cwiseMin(r.group_centre[g] - Vec3::Constant(r.group_radius[g]));
      hi = hi.cwiseMax(r.group_centre[g] + Vec3::Constant(r.group_radius[g]));
    }
    const Vec3 centre = 0.5 * (lo + hi);
    double radius = 0;
    for (size_t g = r.span_first[s]; g < r.span_first[s + 1]; ++g)
      radius = std::max(radius, (r.group_centre[g] - centre).norm() + r.group_radius[g]);
    r.span_centre.push_back(centre);
    r.span_radius.push_back(radius * (1 + 1e-12) + 1e-12);
  }
  fill_reach_lanes(r);
  return r;
}

// The box of the ball's centres under the bones, grown by r once at the end: rounding is monotonic, so the least
// of the rounded x - r is the rounded least x - r, the same bits as growing each centre, in locals the compiler
// keeps in registers (box may alias the bones for all it knows).
void coarse_bounds(const SkinGroup& group, const Vec3& c, double r,
                   const std::array<BoneTransform, kHandJointCount>& bones, double* box) {
  Vec3 lo = Vec3::Constant(std::numeric_limits<double>::infinity()), hi = -lo;
  for (int k = 0; k < group.count; ++k) {
    const BoneTransform& B = bones[group.bones[k]];
    const Vec3 x = B.leftCols<3>() * c + B.col(3);
    lo = lo.cwiseMin(x);
    hi = hi.cwiseMax(x);
  }
  for (int d = 0; d < 3; ++d) {
    box[d] = lo[d] - r;
    box[3 + d] = hi[d] + r;
  }
}

#ifdef HANDSIM_AVX2_KERNELS
namespace {
// coarse_particle_bounds_scalar four bones at a time: each lane's centre with the scalar product's bits (Eigen
// sums rows 0 and 1 of B.leftCols<3>() * j from the left, row 2 from the right), the box the least and most of
// the lanes' (the same numbers: a minimum does not round; only an exact zero's sign could come from another bone).
__attribute__((target("avx2"))) void coarse_particle_bounds_avx2(const HandReach& reach,
                                                                 const std::array<BoneTransform, kHandJointCount>& bones,
                                                                 Vec3& lo, Vec3& hi) {
  using simd4::V4;
  const double inf = std::numeric_limits<double>::infinity();
  V4 low[3] = {simd4::splat(inf), simd4::splat(inf), simd4::splat(inf)};
  V4 high[3] = {-low[0], -low[1], -low[2]};
  for (int first = 0; first < kHandJointCount; first += 4) {
    const int k[4] = {first, first + 1, std::min(first + 2, kHandJointCount - 1),
                      std::min(first + 3, kHandJointCount - 1)};
    const BoneTransform* const b[4] = {&bones[k[0]], &bones[k[1]], &bones[k[2]], &bones[k[3]]};
    V4 m[12];
    simd4::load_bones(b, m);
    const V4 jx = simd4::load(&reach.lanes[0][first]), jy = simd4::load(&reach.lanes[1][first]),
             jz = simd4::load(&reach.lanes[2][first]);
    const V4 r = simd4::load(&reach.lanes[3][first]);  // -inf for a bone that moves no particle: its centre - r is
                                                        // +inf, its centre + r -inf
    for (int i = 0; i < 3; ++i) {
      const V4 a = m[i] * jx, bb = m[3 + i] * jy, c = m[6 + i] * jz;
      const V4 centre = (i < 2 ? (a + bb) + c : a + (bb + c)) + m[9 + i];
      low[i] = _mm256_min_pd(low[i], centre - r);
      high[i] = _mm256_max_pd(high[i], centre + r);
    }
  }
  for (int i = 0; i < 3; ++i) {
    lo[i] = std::min(std::min(low[i][0], low[i][1]), std::min(low[i][2], low[i][3]));
    hi[i] = std::max(std::max(high[i][0], high[i][1]), std::max(high[i][2], high[i][3]));
  }
}
}  // namespace
#endif

void coarse_particle_bounds(const HandReach& reach, const std::array<BoneTransform, kHandJointCount>& bones,
                            Vec3& lo, Vec3& hi) {
#ifdef HANDSIM_AVX2_KERNELS
  if (simd4::has_avx2()) return coarse_particle_bounds_avx2(reach, bones, lo, hi);
#endif
  coarse_particle_bounds_scalar(reach, bones, lo, hi);
}

void coarse_particle_bounds_scalar(const HandReach& reach, const std::array<BoneTransform, kHandJointCount>& bones,
                                   Vec3& lo, Vec3& hi) {
  lo.setConstant(std::numeric_limits<double>::infinity());
  hi = -lo;
  for (int k = 0; k < kHandJointCount; ++k) {
    if (reach.reach[k] < 0) continue;
    const Vec3 c = bones[k].leftCols<3>() * reach.bind_joint[k] + bones[k].col(3);
    lo = lo.cwiseMin(c - Vec3::Constant(reach.reach[k]));
    hi = hi.cwiseMax(c + Vec3::Constant(reach.reach[k]));
  }
}

void hold_group_boxes(const HandReach& reach, Vec3& lo, Vec3& hi) {
  for (int d = 0; d < 3; ++d) {
    const double l = lo[d] - reach.group_excess, u = hi[d] + reach.group_excess;
    lo[d] = l - 1e-9 * (1 + std::abs(l));  // rounding in world coordinates: ~1e-16 of them
    hi[d] = u + 1e-9 * (1 + std::abs(u));
  }
}

namespace {
// Whether the palm went from `a` to `b` in dt faster than the speed cap (m/s or rad/s).
bool teleported(const Pose& a, const Pose& b, double dt) {
  const double angle = a.orientation.angularDistance(b.orientation);
  return (b.position - a.position).norm() > validate::kMaxSpeed * dt || angle > validate::kMaxSpeed * dt;
}
}  // namespace

// --- the frame's input: each hand's bones, palm and the histories they feed (before the held bodies follow their
// hands and anything is skinned) ---
void track_hands(HandParticles& particles, const SlotFrames& frames, double time, StepReport& report, double dt) {
  const WorldDef& def = particles.def;
  std::vector<HandSlot>& hands = particles.hands;
  for (uint32_t i = 0; i < hands.size(); ++i) {
    HandSlot& h = hands[i];
    if (!h.alive) continue;
    const HandFrame* frame = frames[i];
    if (!frame || !frame->tracked()) {
      particles.complete_contacts(i);  // the last frame's lazy contacts and deformation stay readable while it is away
      h.state.tracked = false;
      h.history.clear();  // a hand that comes back elsewhere must not be thrown across the room
      h.grip.clear();     // nor have closed on what it finds there
      h.articulation.clear();
      continue;
    }
    // The frame was validated by validate_step.
    compute_bone_transforms(*h.model, *frame, h.state.bones);
    h.state.tracked = true;
    h.state.displaced.clear();
    h.deformed_current = false;
    h.particles_current = false;
    const Pose palm{frame->joints[kPalm].position, frame->joints[kPalm].orientation.normalized()};
    // A palm that moved faster than the speed cap since its last frame teleported (a tracker glitch, a
    // re-centred play space): its motion history says nothing about the new place, and what it holds arrives
    // there at rest instead of being flung (a 1e6 m jump threw a held cube at 1.8e7 m/s; issue 22).
    if (h.has_pose && teleported(h.palm, palm, dt)) {
      h.history.clear();
      h.articulation.clear();  // nor do its bones' (Wrap's press reads the closing fingers' world motion from them)
      report.warnings |= warning_bit(StepWarning::HandTeleported);
    }
    h.palm = palm;
    h.has_pose = true;
    h.history.push(h.palm, time + dt);  // the frame's end time
    h.grip.push(grip_terms(h.grip_bind, h.state.bones, def.grasp.pinch_reach), h.palm.position, time + dt, def.grasp.closing_window_s);
    // The squeeze reads the articulation over the closing window; Wrap's press the closing fingers' own speed.
    if (keeps_articulation(def))
      h.articulation.push(h.state.bones, time + dt, def.grasp.closing_window_s);
    h.render_dirty = true;
  }
}

// --- lines 1-2: deform the hand mesh (eq. 1, particles only) and update the particles ---
StageReport pose_hands(HandParticles& particles) {
  const WorldDef& def = particles.def;
  const std::vector<Body>& bodies = particles.bodies;
  std::vector<HandSlot>& hands = particles.hands;
  int tracked = 0, in_reach = 0;
  for (auto& entry : particles.pairs) entry.second.still = false;  // set below for the hands near a body
  for (uint32_t i = 0; i < hands.size(); ++i) {
    HandSlot& h = hands[i];
    if (!h.alive || !h.state.tracked) continue;
    // Skin the particles only when the hand's coarse bounds come near a body (the paper: always).
    coarse_particle_bounds(h.reach, h.state.bones, h.state.bounds_lo, h.state.bounds_hi);
    if (def.paper_pipeline) {
      particles.skin_particles(h);
    } else if (particles.near_any_body(h.state.bounds_lo, h.state.bounds_hi)) {
      // The hold path: a pair whose hand holds its body as it held it at the anchor skins only its witness
      // pair (skin_particles_in_reach leaves the body out).
      bool still = false;
      for (auto it = particles.pairs.lower_bound({i, 0}); it != particles.pairs.end() && it->first.first == i; ++it) {
        HandBodyPair& pair = it->second;
        pair.still = particles.hold_path && def.particle_contacts == WorldDef::ParticleContacts::ClosedForm &&
                     particles.holds_still(h, bodies[it->first.second], pair);
        still = still || pair.still;
      }
      in_reach += particles.skin_particles_in_reach(h);
      if (still) particles.skin_witnesses(h);
    } else {
      h.reach_groups.clear();  // far from every body: no contact is possible this frame
      h.reach_groups_only = true;
    }
    if (def.paper_pipeline) particles.skin_render_mesh(h);  // the paper skins the whole mesh every frame, needed or not
    ++tracked;
  }
  if (tracked == 0) return stage_skipped(SkipReason::NoTrackedHand);
  return stage_work(tracked, in_reach);
}

// A hand near a body: only the particle groups whose bone-derived box comes within contact reach of a body
// (its box grown by the particle radius, and by the release distance for a body the hand holds: the margins
// detect_contacts uses) are
// skinned, each with its exact box; the others keep an empty box, so no contact test looks at them, and the
// particles are skinned in full only if something reads them. Returns the number of particles skinned.
int HandParticles::skin_particles_in_reach(HandSlot& h) {
  const HandModel& m = *h.model;
  const SkinLayout& layout = m.particle_skin;
  const double reach = m.particle_radius;
  // The bodies near the hand at all: the only ones its groups need testing against.
  // Each grown by the margin detect_contacts gives it: the release distance for a body this hand holds, none
  // for the others (their contacts need real contact).
  std::vector<double>& near_boxes = scratch.near_boxes;
  near_boxes.clear();
  boxes.bodies_near(h.state.bounds_lo, h.state.bounds_hi, def.grasp.release_distance, &scratch.near_bodies);
  const uint32_t hand = uint32_t(&h - hands.data());
  for (uint32_t bi : scratch.near_bodies) {
    if (bodies[bi].held_by(hand)) {
      auto it = pairs.find({hand, bi});
      if (it != pairs.end() && it->second.still) continue;  // held still: its witness pair is skinned alone
    }
    const double margin = bodies[bi].held_by(hand) ? def.grasp.release_distance : 0.0;
    for (int k = 0; k < 6; ++k) near_boxes.push_back(boxes.body_boxes[6 * bi + k] + (k < 3 ? -margin : margin));
  }
  h.state.tracked_positions.resize(3, Eigen::Index(layout.bind_xyz[0].size()));
  h.group_bounds.resize(6 * layout.groups.size());
  h.reach_groups.clear();
  h.reach_groups_only = true;
  if (near_boxes.empty()) {
    // No body to reach (the hand's only body near is the one it holds still): no group is skinned, and the
    // loop below would only make the hand's bounds from the groups' boxes. The coarse bounds grown by the groups'
    // excess over them (hold_group_boxes) hold every group's box grown by the particle radius, so a body they leave out (detect_contacts, or this function again when
    // the witness lets go) is out of every group's reach, as it is with the loop's bounds. The groups' boxes are
    // left as they are: only reach_groups' are read while reach_groups_only.
    hold_group_boxes(h.reach, h.state.bounds_lo, h.state.bounds_hi);
    h.particles_current = false;
    return 0;
  }
  auto in_reach = [&](const double* box) {
    for (size_t j = 0; j < near_boxes.size(); j += 6)
      if (box[0] - reach <= near_boxes[j + 3] && box[1] - reach <= near_boxes[j + 4] &&
          box[2] - reach <= near_boxes[j + 5] && near_boxes[j] <= box[3] + reach &&
          near_boxes[j + 1] <= box[4] + reach && near_boxes[j + 2] <= box[5] + reach)
        return true;
    return false;
  };
  auto grow = [](Vec3& lo, Vec3& hi, const double* box) {
    lo = lo.cwiseMin(Eigen::Map<const Vec3>(box));
    hi = hi.cwiseMax(Eigen::Map<const Vec3>(box + 3));
  };
  auto empty = [](double* box) {  // no contact prefilter passes an empty box
    std::fill(box, box + 3, std::numeric_limits<double>::infinity());
    std::fill(box + 3, box + 6, -std::numeric_limits<double>::infinity());
  };
  Vec3 lo = Vec3::Constant(std::numeric_limits<double>::infinity()), hi = -lo;
  int count = 0;
  bool all = true;
  const HandReach& r = h.reach;
  for (size_t s = 0; s + 1 < r.span_first.size(); ++s) {
    const size_t first = r.span_first[s], last = r.span_first[s + 1];
    // A span of one group is tested as that group: its ball holds the one group's ball, so its box would only
    // repeat the group's test (the hand's bounds then take the group's box, which the span's holds).
    if (last - first > 1) {
      double span_box[6];
      coarse_bounds(layout.groups[first], r.span_centre[s], r.span_radius[s], h.state.bones, span_box);
      if (!in_reach(span_box)) {  // the whole span is out of reach: its box bounds the hand, its groups are empty
        grow(lo, hi, span_box);
        for (size_t g = first; g < last; ++g) empty(&h.group_bounds[6 * g]);
        all = false;
        continue;
      }
    }
    for (size_t g = first; g < last; ++g) {
      double* box = &h.group_bounds[6 * g];
      coarse_bounds(layout.groups[g], r.group_centre[g], r.group_radius[g], h.state.bones, box);
      if (in_reach(box)) {
        skin_layout(layout, h.state.bones, h.state.tracked_positions.data(), g, g + 1, h.group_bounds.data());
        h.reach_groups.push_back(uint32_t(g));
        count += layout.groups[g].end - layout.groups[g].begin;
        grow(lo, hi, box);  // now the exact box of its centres
      } else {
        grow(lo, hi, box);
        empty(box);
        all = false;
      }
    }
  }
  h.state.bounds_lo = lo.array() - m.particle_radius;
  h.state.bounds_hi = hi.array() + m.particle_radius;
  h.particles_current = all;
  return count;
}

// The witness pairs of the hand's still pairs (hold path): eq. 1 for those particles alone. Their groups keep the
// boxes skin_particles_in_reach gave them (empty unless in reach of another body), so no other body's contact
// test sees them unless it would have.
void HandParticles::skin_witnesses(HandSlot& h) {
  const uint32_t hand = uint32_t(&h - hands.data());
  for (auto it = pairs.lower_bound({hand, 0}); it != pairs.end() && it->first.first == hand; ++it)
    if (it->second.still)
      for (int p : it->second.witness)
        skin_layout_point(h.model->particle_skin, h.state.bones, p, h.state.tracked_positions.data());
}

// Eq. 1 for the particles, with the box of each particle group for the contact prefilter; the hand's bounds
// become the exact box of its particle spheres.
void HandParticles::skin_particles(HandSlot& h) {
  const HandModel& m = *h.model;
  skin_layout(m.particle_skin, h.state.bones, h.state.tracked_positions, &h.group_bounds);
  Vec3 lo = Vec3::Constant(std::numeric_limits<double>::infinity()), hi = -lo;
  for (size_t g = 0; g < m.particle_skin.groups.size(); ++g) {
    lo = lo.cwiseMin(Eigen::Map<const Vec3>(&h.group_bounds[6 * g]));
    hi = hi.cwiseMax(Eigen::Map<const Vec3>(&h.group_bounds[6 * g + 3]));
  }
  h.state.bounds_lo = lo.array() - m.particle_radius;
  h.state.bounds_hi = hi.array() + m.particle_radius;
  h.particles_current = true;
  h.reach_groups_only = false;
}

// Brings the lazily skipped particle positions up to date (same arithmetic as in the step, so same bits).
void HandParticles::refresh_particles(HandSlot& h, bool deformed) {
  if (!h.particles_current) skin_particles(h);
  if (deformed) complete_contacts(uint32_t(&h - hands.data()));  // a held body's lazy contacts deform it too
  if (deformed && !h.deformed_current) {
    h.state.deformed_positions = h.state.tracked_positions;
    for (size_t k = 0; k < h.state.displaced.size(); ++k)  // the particles deform_hands pushed back
      h.state.deformed_positions.col(h.state.displaced[k]) = h.displaced_centres[k];
    h.deformed_current = true;
  }
}

// Whether a box (a hand's coarse bounds) comes within the release distance of any body's bounds: the widest
// margin detect_contacts uses, so a hand that fails this test cannot have a contact.
bool HandParticles::near_any_body(const Vec3& lo, const Vec3& hi) const {
  return boxes.box_near_any_body(lo, hi, def.grasp.release_distance);
}

void HandParticles::skin_render_mesh(HandSlot& h) {
  complete_contacts(uint32_t(&h - hands.data()));  // the deformation reads every contact of the frame
  if (!h.state.displaced.empty()) refresh_particles(h, true);  // the deformation reads the displaced particles
  skin_groups(*h.model, h.state.bones, h.render, def.render_threads);
  apply_render_deformation(*h.model, h.state, h.render);  // reads only displaced particles, which are current
  h.render_dirty = false;
}

}  // namespace handsim
