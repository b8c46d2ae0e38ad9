// The weighted sums of a plane fit over a neighbourhood (weight, first and second moments),
// kept in eight fixed lanes: neighbour j goes to lane j % 8, and the lanes are added up in one
// fixed order at the end. An `omp simd reduction` would let each vector width (two, four or
// eight doubles: simd_clones.h) add the neighbours in its own order, and the same input would
// decompose differently, rounding by rounding, on different CPUs; a level's clustering turns
// those roundings into different points. With fixed lanes every clone adds alike, and the
// module gives the same result bit for bit on any x86-64 (CMakeLists.txt also keeps the
// compiler from fusing multiplies and adds, which only the newer clones could).
#pragma once
#include "pointscale/detail/portable.h"

namespace pointscale {

constexpr int moment_lanes = 8;

struct MomentLanes {
  alignas(64) double w[moment_lanes] = {}, x[moment_lanes] = {}, y[moment_lanes] = {}, z[moment_lanes] = {},
                     xx[moment_lanes] = {}, yy[moment_lanes] = {}, zz[moment_lanes] = {}, xy[moment_lanes] = {},
                     xz[moment_lanes] = {}, yz[moment_lanes] = {};

  // Adds one neighbour's weight and weighted moments (already multiplied by its weight) to lane l.
  POINTSCALE_ALWAYS_INLINE void add(int l, double ww, double wx, double wy, double wz, double wxx, double wyy,
                                    double wzz, double wxy, double wxz, double wyz) {
    w[l] += ww; x[l] += wx; y[l] += wy; z[l] += wz;
    xx[l] += wxx; yy[l] += wyy; zz[l] += wzz;
    xy[l] += wxy; xz[l] += wxz; yz[l] += wyz;
  }
};

// The lanes' total, in a fixed order (pairwise).
POINTSCALE_ALWAYS_INLINE double lanes_total(const double (&a)[moment_lanes]) {
  return ((a[0] + a[1]) + (a[2] + a[3])) + ((a[4] + a[5]) + (a[6] + a[7]));
}

}  // namespace pointscale
