// Four lanes of doubles for the per-bone kernels (bones, the hold check): each lane does the IEEE operations
// of the scalar formula in the same order (no fused multiply-adds: -ffp-contract=off), so a lane gives the
// scalar code's bits. Compiled for AVX2 only and picked at run time (has_avx2); elsewhere the scalar code runs.
#pragma once

#if defined(HANDSIM_SIMD_DISPATCH) && defined(__x86_64__) && defined(__GNUC__) && !defined(__clang__) && \
    defined(__linux__) && !defined(__SANITIZE_THREAD__)
#define HANDSIM_AVX2_KERNELS 1
#include <immintrin.h>

#include <cstring>

#include "handsim/hand.h"

namespace handsim::simd4 {

typedef double V4 __attribute__((vector_size(32)));
#define HANDSIM_AVX2 inline __attribute__((always_inline, target("avx2")))

// Whether this CPU runs the AVX2 kernels (asked once).
inline bool has_avx2() {
  static const bool yes = __builtin_cpu_supports("avx2");
  return yes;
}

HANDSIM_AVX2 V4 load(const double* p) {
  V4 v;
  std::memcpy(&v, p, sizeof v);
  return v;
}
HANDSIM_AVX2 void store(double* p, const V4& v) { std::memcpy(p, &v, sizeof v); }
HANDSIM_AVX2 V4 sqrt(V4 v) { return _mm256_sqrt_pd(v); }
HANDSIM_AVX2 V4 splat(double x) { return V4{x, x, x, x}; }

// Rows a..d of a 4x4 block become its columns (lane k of the results: row k's numbers).
HANDSIM_AVX2 void transpose(V4& a, V4& b, V4& c, V4& d) {
  const V4 t0 = __builtin_shufflevector(a, b, 0, 4, 2, 6), t1 = __builtin_shufflevector(a, b, 1, 5, 3, 7);
  const V4 t2 = __builtin_shufflevector(c, d, 0, 4, 2, 6), t3 = __builtin_shufflevector(c, d, 1, 5, 3, 7);
  a = __builtin_shufflevector(t0, t2, 0, 1, 4, 5);
  b = __builtin_shufflevector(t1, t3, 0, 1, 4, 5);
  c = __builtin_shufflevector(t0, t2, 2, 3, 6, 7);
  d = __builtin_shufflevector(t1, t3, 2, 3, 6, 7);
}

// Row i of R times the lanes' column (x, y, z), summed as Eigen's fixed-size product sums it: rows 0 and 1
// from the left (its two-row packets), row 2 from the right (its scalar sum).
HANDSIM_AVX2 V4 row_times(const Mat3& R, int i, const V4& x, const V4& y, const V4& z) {
  const V4 a = splat(R(i, 0)) * x, b = splat(R(i, 1)) * y, c = splat(R(i, 2)) * z;
  return i < 2 ? (a + b) + c : a + (b + c);
}

// The 12 numbers (column-major) of the bones b[0..3], lane l from b[l].
HANDSIM_AVX2 void load_bones(const BoneTransform* const* b, V4* m) {
  for (int c = 0; c < 12; c += 4) {
    for (int l = 0; l < 4; ++l) m[c + l] = load(b[l]->data() + c);
    transpose(m[c], m[c + 1], m[c + 2], m[c + 3]);
  }
}

}  // namespace handsim::simd4
#endif
