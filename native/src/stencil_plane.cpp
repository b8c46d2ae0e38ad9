#include "pointscale/detail/stencil_plane.h"

#include <cmath>
#include <limits>

#include "pointscale/detail/fast_exp.h"
#include "pointscale/detail/moment_lanes.h"
#include "pointscale/detail/plane_fit.h"
#include "pointscale/detail/portable.h"
#include "pointscale/detail/simd_clones.h"

namespace pointscale {

POINTSCALE_CLONES
void PlaneStencil::assign(const Points& points, const Index* nb, int k, const Eigen::VectorXd& h,
                          const Vec3& origin) {
  if (size != k) {
    for (auto* v : {&x, &y, &z, &xx, &yy, &zz, &xy, &xz, &yz, &inv_h2, &e0, &gx, &gy, &gz}) v->resize(k);
    scratch.resize(8 * static_cast<std::size_t>(k));
    size = k;
  }
  double* __restrict px = x.data();
  double* __restrict py = y.data();
  double* __restrict pz = z.data();
  double* __restrict ih2 = inv_h2.data();
  // The gather, scalar; the loop after it vectorises. inv_h2 holds h until then.
  for (int j = 0; j < k; ++j) {
    px[j] = points(nb[j], 0) - origin.x();
    py[j] = points(nb[j], 1) - origin.y();
    pz[j] = points(nb[j], 2) - origin.z();
    ih2[j] = h(nb[j]);
  }
  double* __restrict pxx = xx.data();
  double* __restrict pyy = yy.data();
  double* __restrict pzz = zz.data();
  double* __restrict pxy = xy.data();
  double* __restrict pxz = xz.data();
  double* __restrict pyz = yz.data();
  double* __restrict pe0 = e0.data();
  double* __restrict pgx = gx.data();
  double* __restrict pgy = gy.data();
  double* __restrict pgz = gz.data();
#pragma omp simd
  for (int j = 0; j < k; ++j) {
    const double a = px[j], b = py[j], c = pz[j];
    const double inv = 1.0 / (ih2[j] * ih2[j]);
    ih2[j] = inv;
    pxx[j] = a * a; pyy[j] = b * b; pzz[j] = c * c;
    pxy[j] = a * b; pxz[j] = a * c; pyz[j] = b * c;
    pe0[j] = (a * a + b * b + c * c) * inv;
    pgx[j] = -2.0 * inv * a; pgy[j] = -2.0 * inv * b; pgz[j] = -2.0 * inv * c;
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

// Queries first .. first + L - 1 of stencil_covariances. With L > 1 lanes are queries, not
// neighbours: every member of the cluster meets the same neighbours, so neighbour j is one
// broadcast value and no horizontal sums are left. Eight lanes fill AVX-512 registers, four
// AVX2 ones; each lane's arithmetic is the same either way. With L = 1 (the rest of a cluster,
// and clusters with a single query, as in the consistency iteration) lanes are neighbours.
template <int L>
POINTSCALE_ALWAYS_INLINE void covariances_of_group(PlaneStencil& stencil, const double* queries, int first,
                                                                double weight_floor, double* cov, double* trace,
                                                                double* valid) {
  const int k = stencil.size;
  const double* __restrict px = stencil.x.data();
  const double* __restrict py = stencil.y.data();
  const double* __restrict pz = stencil.z.data();
  const double* __restrict pxx = stencil.xx.data();
  const double* __restrict pyy = stencil.yy.data();
  const double* __restrict pzz = stencil.zz.data();
  const double* __restrict pxy = stencil.xy.data();
  const double* __restrict pxz = stencil.xz.data();
  const double* __restrict pyz = stencil.yz.data();
  const double* __restrict ih2 = stencil.inv_h2.data();
  const double* __restrict e0 = stencil.e0.data();
  const double* __restrict gx = stencil.gx.data();
  const double* __restrict gy = stencil.gy.data();
  const double* __restrict gz = stencil.gz.data();
  double* __restrict e = stencil.scratch.data();  // #K by L
  if constexpr (L == 1) {
    const double qx = queries[3 * first], qy = queries[3 * first + 1], qz = queries[3 * first + 2];
    const double q2 = qx * qx + qy * qy + qz * qz;
    double min_e = std::numeric_limits<double>::infinity();
#pragma omp simd reduction(min : min_e)
    for (int j = 0; j < k; ++j) {
      e[j] = e0[j] + ih2[j] * q2 + gx[j] * qx + gy[j] * qy + gz[j] * qz;
      min_e = e[j] < min_e ? e[j] : min_e;
    }
    // Neighbours in fixed lanes (moment_lanes.h): the same sums on every CPU.
    MomentLanes s;
    const auto add = [&](int j, int l) POINTSCALE_ALWAYS_INLINE_LAMBDA {
      double w = exp_nonpositive(min_e - e[j]);
      w = w > weight_floor ? w : weight_floor;
      s.add(l, w, w * px[j], w * py[j], w * pz[j], w * pxx[j], w * pyy[j], w * pzz[j], w * pxy[j], w * pxz[j],
            w * pyz[j]);
    };
    int j = 0;
    for (; j + moment_lanes <= k; j += moment_lanes) {
#pragma omp simd
      for (int l = 0; l < moment_lanes; ++l) add(j + l, l);
    }
    for (int l = 0; j + l < k; ++l) add(j + l, l);
    covariance_from_sums(lanes_total(s.w), lanes_total(s.x), lanes_total(s.y), lanes_total(s.z), lanes_total(s.xx),
                         lanes_total(s.yy), lanes_total(s.zz), lanes_total(s.xy), lanes_total(s.xz),
                         lanes_total(s.yz), cov + 6 * first, trace[first], valid[first]);
    return;
  }
  alignas(64) double qx[L], qy[L], qz[L], q2[L], min_e[L];
  for (int l = 0; l < L; ++l) {
    qx[l] = queries[3 * (first + l)];
    qy[l] = queries[3 * (first + l) + 1];
    qz[l] = queries[3 * (first + l) + 2];
    q2[l] = qx[l] * qx[l] + qy[l] * qy[l] + qz[l] * qz[l];
    min_e[l] = std::numeric_limits<double>::infinity();
  }
  for (int j = 0; j < k; ++j) {
#pragma omp simd
    for (int l = 0; l < L; ++l) {
      const double v = e0[j] + ih2[j] * q2[l] + gx[j] * qx[l] + gy[j] * qy[l] + gz[j] * qz[l];
      e[j * L + l] = v;
      min_e[l] = v < min_e[l] ? v : min_e[l];
    }
  }
  // Sums about the origin: the neighbours' products are the stencil's, shared by all queries.
  alignas(64) double sw[L] = {}, sx[L] = {}, sy[L] = {}, sz[L] = {}, sxx[L] = {}, syy[L] = {}, szz[L] = {},
                     sxy[L] = {}, sxz[L] = {}, syz[L] = {};
  for (int j = 0; j < k; ++j) {
#pragma omp simd
    for (int l = 0; l < L; ++l) {
      double w = exp_nonpositive(min_e[l] - e[j * L + l]);
      w = w > weight_floor ? w : weight_floor;
      sw[l] += w; sx[l] += w * px[j]; sy[l] += w * py[j]; sz[l] += w * pz[j];
      sxx[l] += w * pxx[j]; syy[l] += w * pyy[j]; szz[l] += w * pzz[j];
      sxy[l] += w * pxy[j]; sxz[l] += w * pxz[j]; syz[l] += w * pyz[j];
    }
  }
  for (int l = 0; l < L; ++l) {
    const int i = first + l;
    covariance_from_sums(sw[l], sx[l], sy[l], sz[l], sxx[l], syy[l], szz[l], sxy[l], sxz[l], syz[l], cov + 6 * i,
                         trace[i], valid[i]);
  }
}

}  // namespace

POINTSCALE_CLONES
void stencil_covariances(PlaneStencil& stencil, const double* queries, int m, double weight_floor, double* cov,
                         double* trace, double* valid) {
  int first = 0;
  for (; first + 8 <= m; first += 8) covariances_of_group<8>(stencil, queries, first, weight_floor, cov, trace, valid);
  for (; first + 4 <= m; first += 4) covariances_of_group<4>(stencil, queries, first, weight_floor, cov, trace, valid);
  for (; first < m; ++first) covariances_of_group<1>(stencil, queries, first, weight_floor, cov, trace, valid);
}

}  // namespace pointscale
