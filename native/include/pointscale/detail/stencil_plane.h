// The weighted plane of Eq. 3 for many query points against one fixed set of K support points:
// in level_support every point of a cluster is fitted to the same K neighbour clusters. The
// neighbours are gathered once per cluster, structure-of-arrays and relative to the cluster's
// origin, with everything about them that does not depend on the query worked out then, so
// that each query-neighbour pair costs an exponential and a dozen multiply-adds.
#pragma once
#include <vector>

#include "pointscale/types.h"

namespace pointscale {

struct PlaneStencil {
  std::vector<double> x, y, z;            // #K neighbour offsets p from the origin
  std::vector<double> xx, yy, zz, xy, xz, yz;  // #K products of those offsets (second moments)
  std::vector<double> inv_h2;             // #K 1 / h^2 of each neighbour's kernel
  std::vector<double> e0, gx, gy, gz;     // #K |p|^2 / h^2 and -2 p / h^2: the exponent at q is
                                          // e0 + |q|^2 / h^2 + g . q
  std::vector<double> scratch;            // #K by 8 per-query workspace
  int size = 0;

  // Gathers rows nb[0..k) of points, relative to origin, with kernel widths h(nb[j]).
  void assign(const Points& points, const Index* nb, int k, const Eigen::VectorXd& h, const Vec3& origin);
};

// Weighted covariances of the stencil at m query offsets (relative to its origin), with
// Gaussian weights scaled so that the largest is 1 and floored at weight_floor, as
// floored_gaussian_weights forms them (plane_fit.h). The sums are taken about the stencil's
// origin, not about each query: the covariance is the same up to rounding (~1e-15 relative
// for queries within their cluster). For query i:
// cov[6 i .. 6 i + 5] = xx, yy, zz, xy, xz, yz, trace[i], and valid[i] = 0 where the weights
// or the trace vanish (no plane), 1 otherwise. queries #m by 3 row-major.
void stencil_covariances(PlaneStencil& stencil, const double* queries, int m, double weight_floor, double* cov,
                         double* trace, double* valid);

}  // namespace pointscale
