// Consistently oriented PCA normals of a point cloud, from one neighbour search.
#pragma once
#include "pointscale/types.h"

namespace pointscale {

// The orientation graph's width unless a caller asks otherwise. A wider graph joins more
// neighbours across a thin part, whose two sides' normals are antiparallel and so count as
// agreeing under 1 - |n_i . n_j|: one such shortcut turns a whole region inward. A narrower one
// leaves more points without a neighbour across a gap in the sampling, where their only path
// bends around a sharp turn. tests/test_normals.py checks both on the scans.
constexpr int orientation_width = 12;

// points  #P by 3; taken, and freed once the points are renumbered
// k       neighbours of each plane fit (pca_normals)
// width   neighbours of each point in the orientation graph (orient_along_spanning_tree),
//         at most k, the point itself counted: the nearest of the fit's neighbours
// Returns #P by 3 unit normals in the input's numbering (zero rows where no plane fits),
// outward on closed shapes. The work runs on the points renumbered in Z-order, so that it
// reads memory in order whatever order they come in, and gives the same normals for any
// order of the same points (up to neighbours at equal distances). Throws std::invalid_argument
// for what check_normal_estimation (validation.h) refuses, or a width outside [1, k].
Points oriented_normals(Points&& points, int k, int width);

}  // namespace pointscale
