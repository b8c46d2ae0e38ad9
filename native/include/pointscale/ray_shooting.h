// Ray-MLS surface intersection (Adamson and Alexa 2003), for bottom-up encoding (Sec. 6.1):
// a point on the ray is repeatedly moved to where the ray meets the weighted least-squares plane
// fitted around it, until it lies both on the ray and on the surface. Where that iteration fails
// (grazing rays, folds), the crossing nearest the origin within 16 kernel widths is bracketed
// and bisected instead. A hit more than 3 kernel widths from every sample (the zero set runs on
// over holes and past boundaries) counts as a miss.
#pragma once
#include <limits>
#include <vector>

#include "pointscale/decomposition.h"
#include "pointscale/diffusion.h"
#include "pointscale/progress.h"
#include "pointscale/spatial_index.h"

namespace pointscale {

struct RayOptions {
  int neighbors = 24;          // support points in each plane fit
  double tolerance = 1e-9;     // convergence: step along the ray below tolerance x h
  int max_iterations = 50;     // iteration cap per ray
  double max_distance = std::numeric_limits<double>::infinity();  // a hit farther than this from the origin is a miss
  double min_cosine = 0.05;    // a plane within acos(min_cosine) of the ray direction is a miss
};

struct RayHits {
  Points positions;                  // #R by 3 hits; the origin where the ray missed
  Eigen::VectorXd distances;         // #R signed distance along the direction; 0 where missed
  std::vector<unsigned char> missed; // #R 1 where no intersection was found
  std::size_t miss_count = 0;
};

// origins     #R by 3 ray origins
// directions  #R by 3 unit directions; the ray is the whole line o + t d, t of either sign
// support     spatial index on the #S points defining the MLS surface
// h           #S kernel widths
// Throws std::invalid_argument for bad options or rays (validate, check_rays: validation.h).
RayHits shoot_rays(const Points& origins, const Points& directions, const SpatialIndex& support,
                   const Eigen::VectorXd& h, const RayOptions& options, const ProgressStage& stage = {});

struct RayshootReport {
  std::vector<std::size_t> missed;       // k, level 0 first: rays of band l that found no surface
  std::vector<IndexList> missed_points;  // k lists of the points whose ray missed
};

// Bottom-up decomposition by ray shooting (Sec. 6.1). The scale space Q^k = P, Q^{l-1} =
// Psi_{C^{l-1}}(Q^l) is built as in decompose(), C^{l-1} being the decimated Q^l, diffused
// first when `diffusion` is given (Sec. 5.1). Then P^0 = Q^0, and each P^l is where the rays from
// P^{l-1} along its recomputed normals meet the surface S^l of C^l (S^k: the MLS surface of P
// itself with fine_kernel x its spacing, narrow so that it stays close to the samples). So P^k
// resamples the input surface, and reconstruction
// rebuilds P^k exactly. A ray that misses falls back to the orthogonal projection of its
// origin onto S^l, measured along the normal; it is counted in `report`. Checks its input as
// decompose does, and the rays' options and fine_kernel (validation.h).
MultiscaleModel decompose_rayshoot(const Points& points, const Points* input_normals, const DecomposeOptions& options,
                                   const DiffusionOptions* diffusion, const RayOptions& rays, double fine_kernel,
                                   RayshootReport& report, const ProgressCallback* progress = nullptr);

// The decimated support C^{l-1} of one level: centroids of `target` clusters of `fine`, diffused
// when `diffusion` is given (decompose_rayshoot's scale space).
Points smoothed_support(const Points& fine, std::size_t target, double max_variation,
                        const DiffusionOptions* diffusion);

}  // namespace pointscale
