#include "pointscale/stencil_plane.h"

#include <cmath>
#include <limits>

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

namespace {

// The covariance from the sums, as plane_from_sums forms it, written as six entries.
inline void covariance_from_sums(double sw, double sx, double sy, double sz, double sxx, double syy, double szz,
                                 double sxy, double sxz, double syz, double* cov, double& trace, double& valid) {
  const bool weighed = sw > 0.0;
  double m[3];
  moments_from_sums(weighed ? sw : 1.0, sx, sy, sz, sxx, syy, szz, sxy, sxz, syz, m, cov);
  trace = cov[0] + cov[1] + cov[2];
  valid = weighed && trace > 0.0 ? 1.0 : 0.0;
}

}  // namespace

POINTSCALE_CLONES
void stencil_covariances(PlaneStencil& stencil, const double* queries, int m, double weight_floor, double* cov,
                         double* trace, double* valid) {
  const int k = stencil.size;
  const double* __restrict px = stencil.x.data();
  const double* __restrict py = stencil.y.data();
  const double* __restrict pz = stencil.z.data();
  const double* __restrict ih2 = stencil.inv_h2.data();
  double* __restrict e = stencil.scratch.data();  // #K by query_lanes
  // Whole groups of four queries: lanes are queries, not neighbours. Every member of the
  // cluster meets the same neighbours, so neighbour j is one broadcast value and no horizontal
  // sums are left; four at a time keep the ten sums in ten AVX2 registers.
  constexpr int query_lanes = 4;
  const int grouped = m - m % query_lanes;
  for (int first = 0; first < grouped; first += query_lanes) {
    alignas(32) double qx[query_lanes], qy[query_lanes], qz[query_lanes], min_e[query_lanes];
    for (int l = 0; l < query_lanes; ++l) {
      qx[l] = queries[3 * (first + l)];
      qy[l] = queries[3 * (first + l) + 1];
      qz[l] = queries[3 * (first + l) + 2];
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
    for (int l = 0; l < query_lanes; ++l) {
      const int i = first + l;
      covariance_from_sums(sw[l], sx[l], sy[l], sz[l], sxx[l], syy[l], szz[l], sxy[l], sxz[l], syz[l], cov + 6 * i,
                           trace[i], valid[i]);
    }
  }
  // The rest one at a time, lanes over neighbours (clusters with a single query, as in the
  // consistency iteration, all go this way).
  for (int i = grouped; i < m; ++i) {
    const double qx = queries[3 * i], qy = queries[3 * i + 1], qz = queries[3 * i + 2];
    double min_e = std::numeric_limits<double>::infinity();
#pragma omp simd reduction(min : min_e)
    for (int j = 0; j < k; ++j) {
      const double dx = px[j] - qx, dy = py[j] - qy, dz = pz[j] - qz;
      e[j] = (dx * dx + dy * dy + dz * dz) * ih2[j];
      min_e = e[j] < min_e ? e[j] : min_e;
    }
    double sw = 0, sx = 0, sy = 0, sz = 0, sxx = 0, syy = 0, szz = 0, sxy = 0, sxz = 0, syz = 0;
#pragma omp simd reduction(+ : sw, sx, sy, sz, sxx, syy, szz, sxy, sxz, syz)
    for (int j = 0; j < k; ++j) {
      double w = exp_nonpositive(min_e - e[j]);
      w = w > weight_floor ? w : weight_floor;
      const double dx = px[j] - qx, dy = py[j] - qy, dz = pz[j] - qz;
      const double wx = w * dx, wy = w * dy, wz = w * dz;
      sw += w; sx += wx; sy += wy; sz += wz;
      sxx += wx * dx; syy += wy * dy; szz += wz * dz;
      sxy += wx * dy; sxz += wx * dz; syz += wy * dz;
    }
    covariance_from_sums(sw, sx, sy, sz, sxx, syy, szz, sxy, sxz, syz, cov + 6 * i, trace[i], valid[i]);
  }
}

}  // namespace pointscale
