// Making an encoded level's offsets normal (encode_onto, Sec. 8.2).
#pragma once
#include "pointscale/detail/level_normals.h"
#include "pointscale/spatial_index.h"

namespace pointscale {

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

}  // namespace pointscale
