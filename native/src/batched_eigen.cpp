#include "pointscale/detail/batched_eigen.h"

#include "pointscale/detail/simd_clones.h"

namespace pointscale {

POINTSCALE_CLONES
void solve_eigen_batch(const double (&cov)[6][eigen_lanes], const double (&trace)[eigen_lanes],
                       const double (&used)[eigen_lanes], double (&normal)[3][eigen_lanes], double (&ok)[eigen_lanes]) {
  batched_smallest_eigenvectors(cov, trace, used, normal, ok);
}

}  // namespace pointscale
