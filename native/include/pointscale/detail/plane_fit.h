// Weighted least-squares plane through a small set of points (Eq. 2-3 of the paper):
// the weighted average a and the direction of smallest weighted covariance n.
#pragma once
#include <algorithm>
#include <Eigen/Core>
#include <Eigen/Geometry>
#include <cmath>
#include <cstdint>
#include <limits>

#include "pointscale/detail/portable.h"
#include "pointscale/types.h"

namespace pointscale {

struct PlaneFit {
  Vec3 mean = Vec3::Zero();    // a(x), Eq. 2
  Vec3 normal = Vec3::Zero();  // n(x), Eq. 3 (unit, sign arbitrary)
  double variation = 0.0;      // lambda_min / (sum of eigenvalues): surface variation
  bool ok = false;             // false when the weights vanish or the covariance has no plane
};

// Gaussian weights exp(-|p_j - x|^2 / h_j^2), scaled so that the largest is 1. The scaling
// cancels in the fit and keeps points far outside every kernel from underflowing to zero.
// d2[j] = |p_j - x|^2, inv_h2[j] = 1 / h_j^2. Writes `count` weights.
inline void gaussian_weights(const double* d2, const double* inv_h2, int count, double* weights) {
  double min_e = std::numeric_limits<double>::infinity();
  for (int j = 0; j < count; ++j) min_e = std::min(min_e, d2[j] * inv_h2[j]);
  for (int j = 0; j < count; ++j) weights[j] = std::exp(min_e - d2[j] * inv_h2[j]);
}

// A floor on the scaled weights keeps a fit well conditioned where one point dominates: a
// query far from all the others (raw-scan outliers, a ray's origin several kernel widths off
// the surface) otherwise fits a plane to little more than one point, whose normal is noise.
constexpr double weight_floor = 1e-6;

// gaussian_weights, each raised to at least weight_floor.
inline void floored_gaussian_weights(const double* d2, const double* inv_h2, int count, double* weights) {
  gaussian_weights(d2, inv_h2, count, weights);
  for (int j = 0; j < count; ++j) weights[j] = std::max(weights[j], weight_floor);
}

// 2^-e for x = m 2^e with m in [1, 2): an exact rescaling to [1, 2). x must be positive and normal.
inline double inverse_power_of_two(double x) {
  const std::uint64_t exponent = (bit_cast<std::uint64_t>(x) >> 52) & 0x7ff;
  return bit_cast<double>((std::uint64_t(2046) - exponent) << 52);
}

namespace detail {

// The six distinct entries (xx, yy, zz, xy, xz, yz) of the adjugate of the symmetric c; squaring
// only those does half the work of a general 3x3 product.
inline void symmetric_adjugate(const Mat3& c, double* a) {
  const double xx = c(0, 0), yy = c(1, 1), zz = c(2, 2);
  const double xy = c(0, 1), xz = c(0, 2), yz = c(1, 2);
  a[0] = yy * zz - yz * yz; a[1] = xx * zz - xz * xz; a[2] = xx * yy - xy * xy;
  a[3] = xz * yz - xy * zz; a[4] = xy * yz - xz * yy; a[5] = xy * xz - xx * yz;
}

inline double max_abs6(const double* m) {
  double out = 0.0;
  for (int j = 0; j < 6; ++j) out = std::max(out, std::abs(m[j]));
  return out;
}

// Squares the symmetric matrix a (six entries) until it is rank one to working precision
// and returns its dominant column, normalised. Each squaring squares the ratio d of its two
// largest eigenvalues, and tr^2 - |A|^2 is about 2 d tr^2. That difference is only known to a
// few ulp of tr^2, so the test asks for d below about 5e-9, which rounding cannot fake, and
// one more squaring takes d below 2.5e-17, under the rounding of the result: at most one
// squaring more than needed, where a test at the rounding level could pass only by chance and
// take several more. The iterates are positive semi-definite after the first squaring, so their trace
// bounds every entry: rescaling by the power of two nearest below 1 / trace keeps them in
// range, exactly and without a division on the critical path.
constexpr double rank_one_test = 1e-8;

inline Vec3 dominant_by_squaring(double* a) {
  bool last = false;  // the test passed: this squaring is the final one
  for (int i = 0; i < 10; ++i) {
    const double xx = a[0], yy = a[1], zz = a[2], xy = a[3], xz = a[4], yz = a[5];
    const double b[6] = {xx * xx + xy * xy + xz * xz, xy * xy + yy * yy + yz * yz, xz * xz + yz * yz + zz * zz,
                         xx * xy + xy * yy + xz * yz, xx * xz + xy * yz + xz * zz, xy * xz + yy * yz + yz * zz};
    const double inv = inverse_power_of_two(b[0] + b[1] + b[2]);
    for (int j = 0; j < 6; ++j) a[j] = b[j] * inv;
    if (last) break;
    const double tr = a[0] + a[1] + a[2];
    const double norm2 = a[0] * a[0] + a[1] * a[1] + a[2] * a[2] + 2.0 * (a[3] * a[3] + a[4] * a[4] + a[5] * a[5]);
    last = tr * tr - norm2 <= rank_one_test * tr * tr;
  }
  const Vec3 cols[3] = {Vec3(a[0], a[3], a[4]), Vec3(a[3], a[1], a[5]), Vec3(a[4], a[5], a[2])};
  int best = 0;
  for (int j = 1; j < 3; ++j) if (cols[j].squaredNorm() > cols[best].squaredNorm()) best = j;
  return cols[best].normalized();
}

}  // namespace detail

// Unit eigenvector of the smallest eigenvalue of a symmetric positive semi-definite 3x3 matrix,
// or a zero vector when two eigenvalues vanish (no plane). The adjugate has the same
// eigenvectors with eigenvalues (l2 l3, l1 l3, l1 l2), so its dominant one is the normal; each
// squaring squares the ratio l1 / l2. No trigonometry, no division in the loop (Newton's method
// on det(c - s I) would divide at each step), and deterministic.
inline Vec3 smallest_eigenvector(const Mat3& c, double trace) {
  double a[6];
  detail::symmetric_adjugate(c, a);
  const double scale = detail::max_abs6(a);
  if (!(scale > 1e-24 * trace * trace)) return Vec3::Zero();
  for (double& v : a) v /= scale;
  return detail::dominant_by_squaring(a);
}

// The weighted mean m (relative to where the sums were taken) and covariance c (entries xx,
// yy, zz, xy, xz, yz) from the sums w_sum = sum w, s.. = sum w d, s.. = sum w d d^T; w_sum > 0.
// Plain scalars and no branch, so that it stays cheap inside the vectorised kernels.
inline void moments_from_sums(double w_sum, double sx, double sy, double sz, double sxx, double syy, double szz,
                              double sxy, double sxz, double syz, double* m, double* c) {
  const double inv = 1.0 / w_sum;
  m[0] = sx * inv; m[1] = sy * inv; m[2] = sz * inv;
  c[0] = sxx * inv - m[0] * m[0]; c[1] = syy * inv - m[1] * m[1]; c[2] = szz * inv - m[2] * m[2];
  c[3] = sxy * inv - m[0] * m[1]; c[4] = sxz * inv - m[0] * m[2]; c[5] = syz * inv - m[1] * m[2];
}

// The plane from the weighted sums over points taken relative to `reference`
// (moments_from_sums).
inline PlaneFit plane_from_sums(double w_sum, const Vec3& s, double sxx, double syy, double szz, double sxy,
                                double sxz, double syz, const Vec3& reference) {
  PlaneFit fit;
  if (!(w_sum > 0.0)) return fit;
  double mm[3], c[6];
  moments_from_sums(w_sum, s.x(), s.y(), s.z(), sxx, syy, szz, sxy, sxz, syz, mm, c);
  const Vec3 m(mm[0], mm[1], mm[2]);
  Mat3 cov;
  cov << c[0], c[3], c[4], c[3], c[1], c[5], c[4], c[5], c[2];
  fit.mean = reference + m;
  const double trace = cov.trace();
  if (!(trace > 0.0)) return fit;
  // Two vanishing eigenvalues (collinear or a single point) leave the adjugate at zero.
  const Vec3 normal = smallest_eigenvector(cov, trace);
  if (!(normal.squaredNorm() > 0.5)) return fit;
  fit.normal = normal;
  fit.variation = std::max(0.0, normal.dot(cov * normal)) / trace;
  fit.ok = true;
  return fit;
}

// Fits the plane through points rows `indices[0..count)` of `points` with `weights`.
// `reference` is any nearby point; sums are taken relative to it for precision.
inline PlaneFit fit_weighted_plane(const Points& points, const Index* indices, const double* weights,
                                   int count, const Vec3& reference) {
  PlaneFit fit;
  double w_sum = 0.0;
  Vec3 s = Vec3::Zero();
  Mat3 ss = Mat3::Zero();
  for (int j = 0; j < count; ++j) {
    const double w = weights[j];
    const Vec3 d = points.row(indices[j]).transpose() - reference;
    w_sum += w;
    s += w * d;
    ss.noalias() += w * d * d.transpose();
  }
  return plane_from_sums(w_sum, s, ss(0, 0), ss(1, 1), ss(2, 2), ss(0, 1), ss(0, 2), ss(1, 2), reference);
}

}  // namespace pointscale
