// Encoding a model onto a user-given base surface (Sec. 8.2, Fig. 8): one detail band over a base
// that is not a low-pass version of the model, such as an ellipsoid.
#pragma once
#include "pointscale/decomposition.h"

namespace pointscale {

struct EncodeOptions {
  double kernel = 1.0;         // h = kernel x local spacing of the base samples
  MlsOptions mls;              // projection onto the base
  double max_variation = 0.05; // clustering of the projected points into the level's support
  int consistency_iterations = 200;  // cap for making offsets exactly normal
};

// points  #P by 3 model samples (the caller centres them)
// base    #B by 3 samples of the base surface; the model may lie far outside its kernels: the
//         weights are scaled before exponentiation and neighbourhoods are k-nearest, never empty
// base_normals  #B by 3 or nullptr: orients the base (else outward by propagation)
// Returns a one-band MultiscaleModel: P^0 on the base's MLS surface, D^0 the normal offsets,
// made consistent with the normals that reconstruction recomputes. reports[0].pinned counts the
// points left inconsistent (see align_offsets), consistency_residual their largest error.
MultiscaleModel encode_onto(const Points& points, const Points& base, const Points* base_normals,
                            const EncodeOptions& options, const ProgressCallback* progress = nullptr);

// Closest points on the MLS surface of `base` for points that may lie far from it (many kernel
// widths, beyond the surface's radius of curvature). mls_project's fixed-point iteration swings
// with slope -distance x curvature there, so this starts at the nearest sample, where the first
// fit is well posed, scales each step by 1 / (1 + distance x curvature) with the curvature seen
// between the last two feet (a Newton step), and halves it further whenever a step grows.
// x  #X by 3; base  index on the #B samples; h  #B kernel widths.
MlsResult project_from_afar(const Points& x, const SpatialIndex& base, const Eigen::VectorXd& h,
                            const MlsOptions& options, const ProgressStage& stage = {});

struct Alignment {
  int iterations = 0;
  std::size_t kept = 0;    // points left where they were: no consistent position within reach
  double residual = 0.0;   // largest tangential part of fine - level left, in coordinates
};

// Makes fine - level lie along the level's recomputed normals, moving each level point within
// its tangent plane (anchors by damped iteration, then every other point in one step, since its
// normal does not depend on it). A point whose consistent position lies farther than its
// cluster's kernel width and a twentieth of its offset stays where it was: near a model's
// parts beyond the base's centres of curvature the condition has no stable solution, and moving
// such points would drag the level off the base. reference #P by 3 orients the normals.
// surface, surface_h: when given, every slide is followed by a step along the point's normal back
// onto this MLS surface (which keeps fine - level along the normal), so the level stays on it.
Alignment align_offsets(const Points& fine, Points& level, const LevelSupport& support, const Points& reference,
                        int max_iterations, double stop, const ProgressStage& stage = {},
                        const SpatialIndex* surface = nullptr, const Eigen::VectorXd* surface_h = nullptr,
                        int surface_neighbors = 24);

// The support of a level (clusters, anchors, neighbourhoods, kernels, frames) from its points:
// clusters of `level` down to `target`, kernels = kernel x spacing of the anchors.
LevelSupport build_level_support(const Points& fine, const Points& level, std::size_t target, double kernel,
                                 int neighbors, double max_variation);

// Oriented reference normals for level 0 (outward on closed shapes), per point.
Points orientation_reference(const Points& level, const LevelSupport& support);

// Unit normals of the base samples, oriented outward by propagation (#B by 3).
Points oriented_normals(const SpatialIndex& base);

// Per query point, the oriented normal of its nearest base sample: #Q by 3 orientation references.
Points nearest_normals(const Points& query, const SpatialIndex& base, const Points& base_normals);

}  // namespace pointscale
