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
  x.resize(k); y.resize(k); z.resize(k); inv_h2.resize(k); scratch.resize(k);
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
  double* __restrict e = stencil.scratch.data();
  // The sums of eight queries, then their eigenvectors together.
  for (int first = 0; first < m; first += eigen_lanes) {
    alignas(64) double cov[6][eigen_lanes], trace[eigen_lanes], normal[3][eigen_lanes];
    alignas(64) double used[eigen_lanes], found[eigen_lanes];
    for (int l = 0; l < eigen_lanes; ++l) {
      const int i = first + l;
      used[l] = 0.0;
      // An unused lane holds a harmless plane.
      cov[0][l] = 0.0; cov[1][l] = 1.0; cov[2][l] = 1.0; cov[3][l] = cov[4][l] = cov[5][l] = 0.0;
      trace[l] = 2.0;
      if (i >= m) continue;
      const double qx = queries[3 * i], qy = queries[3 * i + 1], qz = queries[3 * i + 2];
      double min_e = std::numeric_limits<double>::infinity();
#pragma omp simd reduction(min : min_e)
      for (int j = 0; j < k; ++j) {
        const double dx = px[j] - qx, dy = py[j] - qy, dz = pz[j] - qz;
        e[j] = (dx * dx + dy * dy + dz * dz) * ih2[j];
        min_e = e[j] < min_e ? e[j] : min_e;
      }
      // Sums relative to the query, as fit_weighted_plane takes them.
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
      // The covariance, as plane_from_sums forms it (up to rounding).
      if (!(sw > 0.0)) continue;
      const double inv_sw = 1.0 / sw;
      const Vec3 mean = Vec3(sx, sy, sz) * inv_sw;
      Mat3 c;
      c << sxx, sxy, sxz, sxy, syy, syz, sxz, syz, szz;
      c = c * inv_sw - mean * mean.transpose();
      const double tr = c.trace();
      if (!(tr > 0.0)) continue;
      cov[0][l] = c(0, 0); cov[1][l] = c(1, 1); cov[2][l] = c(2, 2);
      cov[3][l] = c(0, 1); cov[4][l] = c(0, 2); cov[5][l] = c(1, 2);
      trace[l] = tr;
      used[l] = 1.0;
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
