// Diffusion smoothing of a point cloud (Sec. 5.1): explicit Euler steps v' = v + lambda Lv (Eq. 12)
// with the umbrella Laplacian over k-nearest-neighbour sets, and Taubin's lambda|mu variant,
// whose second, negative step undoes the shrinkage that plain Laplacian smoothing causes (Sec. 5.3).
#pragma once
#include "pointscale/progress.h"
#include "pointscale/types.h"

namespace pointscale {

struct DiffusionOptions {
  int neighbors = 10;       // K, the point itself included (as knn_graph returns it)
  double lambda = 0.5;      // step of Eq. 12, in (0, 1]
  double mu = 0.0;          // Taubin's second step, mu < -lambda; 0 for plain Laplacian smoothing
  int iterations = 10;      // lambda (and mu) steps
};

// Taubin's mu for a pass-band frequency k_pb: 1/lambda + 1/mu = k_pb (k_pb = 0.1 is his default).
double taubin_mu(double lambda, double pass_band = 0.1);

// points         #P by 3
// neighborhoods  #P by K rows from knn_graph (itself first), computed once and cached: the
//                neighbour sets stay fixed while points move, which keeps points from clustering
// Returns the smoothed #P by 3 points.
Points diffuse(const Points& points, const IndexList& neighborhoods, int k, const DiffusionOptions& options,
               const ProgressStage& stage = {});

// The same, computing the cached neighbourhoods first (K = options.neighbors). Throws
// std::invalid_argument for options or points that validation.h refuses.
Points diffuse(const Points& points, const DiffusionOptions& options, const ProgressStage& stage = {});

}  // namespace pointscale
