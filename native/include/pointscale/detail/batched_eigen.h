// smallest_eigenvector (plane_fit.h) for sixteen matrices at once, one per SIMD lane: the same
// operations in the same order for each lane, each lane frozen once it has converged, so every
// result equals what that lane would give alone, whatever the other lanes hold. The squaring
// loop is latency-bound scalar code; sixteen lanes (two AVX-512 registers per value) share its latency.
#pragma once
#include <cmath>
#include <cstdint>

#include "pointscale/detail/plane_fit.h"
#include "pointscale/detail/portable.h"

namespace pointscale {

constexpr int eigen_lanes = 16;

// cov[0..5][lane]: the entries xx, yy, zz, xy, xz, yz of a symmetric positive semi-definite
// matrix; trace[lane] > 0. used[lane] = 0 marks an unused lane (its cov must still be finite).
// Writes unit normals to normal[0..2][lane] and ok[lane] (0: no plane, as in
// smallest_eigenvector's zero vector, or an unused lane; 1 otherwise).
// Always inlined, so that it is compiled for the caller's SIMD target (simd_clones.h).
POINTSCALE_ALWAYS_INLINE void batched_smallest_eigenvectors(const double (&cov)[6][eigen_lanes], const double (&trace)[eigen_lanes],
                                          const double (&used)[eigen_lanes], double (&normal)[3][eigen_lanes],
                                          double (&ok)[eigen_lanes]) {
  // Written lane by lane with named scalars and selects only, so that the lane loops vectorise.
  alignas(64) double a0[eigen_lanes], a1[eigen_lanes], a2[eigen_lanes], a3[eigen_lanes], a4[eigen_lanes],
      a5[eigen_lanes];
  alignas(64) double done[eigen_lanes];  // 1 once converged (or no plane)
  alignas(64) double last[eigen_lanes];  // 1 once the test passed: one squaring to go
#pragma omp simd
  for (int l = 0; l < eigen_lanes; ++l) {
    const double xx = cov[0][l], yy = cov[1][l], zz = cov[2][l], xy = cov[3][l], xz = cov[4][l], yz = cov[5][l];
    const double b0 = yy * zz - yz * yz, b1 = xx * zz - xz * xz, b2 = xx * yy - xy * xy;
    const double b3 = xz * yz - xy * zz, b4 = xy * yz - xz * yy, b5 = xy * xz - xx * yz;
    double scale = std::fabs(b0);
    scale = std::fabs(b1) > scale ? std::fabs(b1) : scale;
    scale = std::fabs(b2) > scale ? std::fabs(b2) : scale;
    scale = std::fabs(b3) > scale ? std::fabs(b3) : scale;
    scale = std::fabs(b4) > scale ? std::fabs(b4) : scale;
    scale = std::fabs(b5) > scale ? std::fabs(b5) : scale;
    const bool plane = (used[l] != 0.0) & (scale > 1e-24 * trace[l] * trace[l]);  // no short circuit: no branch
    const double inv = 1.0 / (plane ? scale : 1.0);
    a0[l] = plane ? b0 * inv : 1.0;
    a1[l] = plane ? b1 * inv : 0.0;
    a2[l] = plane ? b2 * inv : 0.0;
    a3[l] = plane ? b3 * inv : 0.0;
    a4[l] = plane ? b4 * inv : 0.0;
    a5[l] = plane ? b5 * inv : 0.0;
    ok[l] = plane ? 1.0 : 0.0;
    done[l] = plane ? 0.0 : 1.0;
    last[l] = 0.0;
  }
  for (int i = 0; i < 10; ++i) {
    // (No `omp simd reduction` here: its private copies stop GCC from vectorising this loop.)
    for (int l = 0; l < eigen_lanes; ++l) {
      const double xx = a0[l], yy = a1[l], zz = a2[l], xy = a3[l], xz = a4[l], yz = a5[l];
      const double b0 = xx * xx + xy * xy + xz * xz, b1 = xy * xy + yy * yy + yz * yz,
                   b2 = xz * xz + yz * yz + zz * zz, b3 = xx * xy + xy * yy + xz * yz,
                   b4 = xx * xz + xy * yz + xz * zz, b5 = xy * xz + yy * yz + yz * zz;
      const double inv = inverse_power_of_two(b0 + b1 + b2);
      const double c0 = b0 * inv, c1 = b1 * inv, c2 = b2 * inv, c3 = b3 * inv, c4 = b4 * inv, c5 = b5 * inv;
      const double tr = c0 + c1 + c2;
      const double norm2 = c0 * c0 + c1 * c1 + c2 * c2 + 2.0 * (c3 * c3 + c4 * c4 + c5 * c5);
      const bool frozen = done[l] != 0.0;
      a0[l] = frozen ? xx : c0;
      a1[l] = frozen ? yy : c1;
      a2[l] = frozen ? zz : c2;
      a3[l] = frozen ? xy : c3;
      a4[l] = frozen ? xz : c4;
      a5[l] = frozen ? yz : c5;
      // As dominant_by_squaring: one squaring after the test passes, then frozen.
      const bool passed = tr * tr - norm2 <= detail::rank_one_test * tr * tr;
      done[l] = (frozen | (last[l] != 0.0)) ? 1.0 : 0.0;
      last[l] = passed ? 1.0 : 0.0;
    }
    bool all_done = true;
    for (int l = 0; l < eigen_lanes; ++l) all_done = all_done && done[l] != 0.0;
    if (all_done) break;
  }
  // The column of largest norm, normalised (the first of equal ones, as smallest_eigenvector).
#pragma omp simd
  for (int l = 0; l < eigen_lanes; ++l) {
    const double n0 = a0[l] * a0[l] + a3[l] * a3[l] + a4[l] * a4[l];
    const double n1 = a3[l] * a3[l] + a1[l] * a1[l] + a5[l] * a5[l];
    const double n2 = a4[l] * a4[l] + a5[l] * a5[l] + a2[l] * a2[l];
    const bool one = n1 > n0;
    const double best01 = one ? n1 : n0;
    const bool two = n2 > best01;
    const double len2 = two ? n2 : best01;
    const double x = two ? a4[l] : (one ? a3[l] : a0[l]);
    const double y = two ? a5[l] : (one ? a1[l] : a3[l]);
    const double z = two ? a2[l] : (one ? a5[l] : a4[l]);
    const double inv = 1.0 / std::sqrt(len2);
    normal[0][l] = x * inv;
    normal[1][l] = y * inv;
    normal[2][l] = z * inv;
  }
}

// The same, compiled for the best SIMD target of the machine (simd_clones.h), for callers
// that are not themselves.
void solve_eigen_batch(const double (&cov)[6][eigen_lanes], const double (&trace)[eigen_lanes],
                       const double (&used)[eigen_lanes], double (&normal)[3][eigen_lanes], double (&ok)[eigen_lanes]);

}  // namespace pointscale
