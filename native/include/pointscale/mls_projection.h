// The MLS projection operator Psi (Sec. 2), almost-orthogonal variant: fit the weighted plane at
// the current foot point, project the ORIGINAL point onto it, repeat. At the fixed point the
// offset is exactly along the fitted normal, so a scalar detail coefficient loses nothing.
#pragma once
#include "pointscale/progress.h"
#include "pointscale/spatial_index.h"

namespace pointscale {

struct MlsOptions {
  int neighbors = 24;         // support points in each plane fit
  double tolerance = 1e-7;    // convergence: foot-point step below tolerance x h
  int max_iterations = 30;    // iteration cap per point
};

struct MlsResult {
  Points positions;           // #X by 3 projected points
  Points normals;             // #X by 3 unit normals of the surface there (sign arbitrary)
  std::size_t not_converged = 0;  // points that hit the iteration cap
  std::size_t degenerate = 0;     // points whose neighbourhood defines no plane (left in place)
};

// x        #X by 3 points to project
// support  spatial index on the #S support points that define the surface
// h        #S kernel widths, one per support point (weights exp(-r^2/h_j^2))
MlsResult mls_project(const Points& x, const SpatialIndex& support, const Eigen::VectorXd& h,
                      const MlsOptions& options, const ProgressStage& stage = {});

}  // namespace pointscale
