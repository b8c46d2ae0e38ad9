// The weighted plane of Eq. 3 for many query points against one fixed set of K support points:
// in level_support every point of a cluster is fitted to the same K neighbour clusters. The
// neighbours are gathered once per cluster, structure-of-arrays and relative to the cluster's
// origin, so that the loops over them vectorise.
#pragma once
#include <vector>

#include "pointscale/types.h"

namespace pointscale {

struct PlaneStencil {
  std::vector<double> x, y, z;  // #K neighbour offsets from the origin
  std::vector<double> inv_h2;   // #K 1 / h^2 of each neighbour's kernel
  std::vector<double> scratch;  // #K by 4 per-query workspace
  int size = 0;

  // Gathers rows nb[0..k) of points, relative to origin, with kernel widths h(nb[j]).
  void assign(const Points& points, const Index* nb, int k, const Eigen::VectorXd& h, const Vec3& origin);
};

// Weighted covariances of the stencil at m query offsets (relative to its origin), with
// Gaussian weights scaled so that the largest is 1 and floored at weight_floor, as
// fit_weighted_plane over gaussian_weights forms them before its eigen solve. For query i:
// cov[6 i .. 6 i + 5] = xx, yy, zz, xy, xz, yz, trace[i], and valid[i] = 0 where the weights
// or the trace vanish (no plane), 1 otherwise. queries #m by 3 row-major.
void stencil_covariances(PlaneStencil& stencil, const double* queries, int m, double weight_floor, double* cov,
                         double* trace, double* valid);

}  // namespace pointscale
