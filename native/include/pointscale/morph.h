// Morphing through a common base surface (Sec. 8.3, Eq. 22): both models are projected onto the
// base, and B's normal offsets are carried onto A's samples by k-nearest-neighbour interpolation,
// so p_i(alpha, beta) = p_i + (alpha d_i^A + beta d_i^B) n_i. Where both fold over the base,
// so that the neighbours come from two or more sheets of each, only the sheet of B matching
// A's sample is interpolated: the same rank along the normal, or the nearest.
#pragma once
#include "pointscale/mls_projection.h"

namespace pointscale {

// Gaussian-weighted k-nearest-neighbour interpolation of per-point values.
// from    #F by 3 points carrying the values; values #F
// to      #T by 3 query points; each takes the weighted mean over its k nearest `from` points,
//         with the kernel width set by the k-th neighbour distance (exact at coincident points)
// Returns #T values. Throws std::invalid_argument for points that are not finite, values of
// another size than #F, or k outside [1, max_neighbors].
Eigen::VectorXd knn_interpolate(const Points& from, const Eigen::VectorXd& values, const Points& to, int k);

struct MorphOptions {
  double kernel = 1.0;          // h = kernel x local spacing of the base samples
  MlsOptions mls;               // projection onto the base
  int interpolation_neighbors = 8;
};

struct MorphModel {
  Points base;                  // #A by 3 P'_A: A's samples projected onto the base
  Points normals;               // #A by 3 oriented base normals there (outward on closed bases)
  Eigen::VectorXd detail_a;     // #A d^A: A = base + detail_a * normals
  Eigen::VectorXd detail_b;     // #A d^B interpolated from B's projection onto the base
  std::size_t not_converged = 0;  // projections (of A and B) that hit the iteration cap
  std::size_t degenerate = 0;     // projections with no plane in their neighbourhood
};

// a  #A by 3, b  #B by 3 (the point counts may differ); base  #S by 3 samples of the common base;
// base_normals  #S by 3 or nullptr (then oriented outward by propagation).
// Throws std::invalid_argument for input that validation.h refuses (messages name the models
// points_a and points_b and the base base_points, as the package does).
MorphModel morph(const Points& a, const Points& b, const Points& base, const Points* base_normals,
                 const MorphOptions& options, const ProgressCallback* progress = nullptr);

}  // namespace pointscale
