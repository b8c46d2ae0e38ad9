#include "pointscale/stencil_plane.h"

#include <cmath>
#include <limits>

#include "pointscale/batched_eigen.h"
#include "pointscale/fast_exp.h"
#include "pointscale/plane_fit.h"
#include "pointscale/simd_clones.h"

namespace pointscale {

void PlaneStencil::assign(const Points& points, const Index* nb, int k, const Eigen::VectorXd& h,
                          const Vec3& origin) {
  size = k;
  x.resize(k); y.resize(k); z.resize(k); inv_h2.resize(k); scratch.resize(4 * static_cast<std::size_t>(k));
  for (int j = 0; j < k; ++j) {
    x[j] = points(nb[j], 0) - origin.x();
    y[j] = points(nb[j], 1) - origin.y();
    z[j] = points(nb[j], 2) - origin.z();
    const double hj = h(nb[j]);
    inv_h2[j] = 1.0 / (hj * hj);
  }
}

POINTSCALE_CLONES
void stencil_normals(PlaneStencil& stencil, const double* queries, int m, double weight_floor, double* normals,
                     unsigned char* ok) {
  const int k = stencil.size;
  const double* __restrict px = stencil.x.data();
  const double* __restrict py = stencil.y.data();
  const double* __restrict pz = stencil.z.data();
  const double* __restrict ih2 = stencil.inv_h2.data();
  double* __restrict e = stencil.scratch.data();  // #K by query_lanes
  // Lanes are queries, not neighbours: every member of the cluster meets the same neighbours, so
  // neighbour j is one broadcast value and the loops need no horizontal sums. Four queries at a
  // time keep the ten sums in ten AVX2 registers; their eigenvectors go eight at a time.
  constexpr int query_lanes = 4;
  for (int first = 0; first < m; first += eigen_lanes) {
    alignas(64) double cov[6][eigen_lanes], trace[eigen_lanes], normal[3][eigen_lanes];
    alignas(64) double used[eigen_lanes], found[eigen_lanes];
    for (int half = 0; half < eigen_lanes; half += query_lanes) {
      alignas(32) double qx[query_lanes], qy[query_lanes], qz[query_lanes], min_e[query_lanes];
      for (int l = 0; l < query_lanes; ++l) {
        const int i = first + half + l;
        const bool real = i < m;  // a spare lane computes at the origin and is dropped
        qx[l] = real ? queries[3 * i] : 0.0;
        qy[l] = real ? queries[3 * i + 1] : 0.0;
        qz[l] = real ? queries[3 * i + 2] : 0.0;
        min_e[l] = std::numeric_limits<double>::infinity();
      }
      for (int j = 0; j < k; ++j) {
#pragma omp simd
        for (int l = 0; l < query_lanes; ++l) {
          const double dx = px[j] - qx[l], dy = py[j] - qy[l], dz = pz[j] - qz[l];
          const double v = (dx * dx + dy * dy + dz * dz) * ih2[j];
          e[j * query_lanes + l] = v;
          min_e[l] = v < min_e[l] ? v : min_e[l];
        }
      }
      // Sums relative to each query, as fit_weighted_plane takes them.
      alignas(32) double sw[query_lanes] = {}, sx[query_lanes] = {}, sy[query_lanes] = {}, sz[query_lanes] = {},
                         sxx[query_lanes] = {}, syy[query_lanes] = {}, szz[query_lanes] = {}, sxy[query_lanes] = {},
                         sxz[query_lanes] = {}, syz[query_lanes] = {};
      for (int j = 0; j < k; ++j) {
#pragma omp simd
        for (int l = 0; l < query_lanes; ++l) {
          double w = exp_nonpositive(min_e[l] - e[j * query_lanes + l]);
          w = w > weight_floor ? w : weight_floor;
          const double dx = px[j] - qx[l], dy = py[j] - qy[l], dz = pz[j] - qz[l];
          const double wx = w * dx, wy = w * dy, wz = w * dz;
          sw[l] += w; sx[l] += wx; sy[l] += wy; sz[l] += wz;
          sxx[l] += wx * dx; syy[l] += wy * dy; szz[l] += wz * dz;
          sxy[l] += wx * dy; sxz[l] += wx * dz; syz[l] += wy * dz;
        }
      }
      // The covariance, as plane_from_sums forms it (up to rounding); an unused lane holds a
      // harmless plane.
#pragma omp simd
      for (int l = 0; l < query_lanes; ++l) {
        const int lane = half + l;
        const bool weighed = (first + lane < m) & (sw[l] > 0.0);
        const double inv = 1.0 / (weighed ? sw[l] : 1.0);
        const double mx = sx[l] * inv, my = sy[l] * inv, mz = sz[l] * inv;
        const double cxx = sxx[l] * inv - mx * mx, cyy = syy[l] * inv - my * my, czz = szz[l] * inv - mz * mz;
        const double tr = cxx + cyy + czz;
        const bool valid = weighed & (tr > 0.0);
        cov[0][lane] = valid ? cxx : 0.0;
        cov[1][lane] = valid ? cyy : 1.0;
        cov[2][lane] = valid ? czz : 1.0;
        cov[3][lane] = valid ? sxy[l] * inv - mx * my : 0.0;
        cov[4][lane] = valid ? sxz[l] * inv - mx * mz : 0.0;
        cov[5][lane] = valid ? syz[l] * inv - my * mz : 0.0;
        trace[lane] = valid ? tr : 2.0;
        used[lane] = valid ? 1.0 : 0.0;
      }
    }
    batched_smallest_eigenvectors(cov, trace, used, normal, found);
    for (int l = 0; l < eigen_lanes && first + l < m; ++l) {
      const int i = first + l;
      ok[i] = found[l] != 0.0;
      for (int j = 0; j < 3; ++j) normals[3 * i + j] = normal[j][l];
    }
  }
}

}  // namespace pointscale
