// Point normals from local plane fits, and their consistent orientation.
#pragma once
#include "pointscale/progress.h"
#include "pointscale/spatial_index.h"

namespace pointscale {

// Unit PCA normals of the k-neighbourhood of every point (sign arbitrary). Points whose
// neighbourhood has no plane get a zero row. Returns #P by 3.
Points pca_normals(const SpatialIndex& index, int k, const ProgressStage& stage = {});

// The same, from the same search, also keeping every point's min(width, k) nearest (itself
// among them) in `rows` (#P by that width, row-major), the graph that orient_along_spanning_tree
// takes: one search serves the fits and the orientation.
Points pca_normals(const SpatialIndex& index, int k, int width, IndexList& rows, const ProgressStage& stage = {});

// Flips rows of `normals` (#P by 3) so that they agree along a minimum spanning tree of the
// k-nearest-neighbour graph weighted by 1 - |n_i . n_j| (orient_along_spanning_tree), so
// that closed shapes end up with outward normals. reflect: weigh and sign each edge by one
// normal reflected across the plane halfway between the points (angle_sorted_edges.h), for a
// graph that reaches across thin parts.
void orient_normals(const SpatialIndex& index, Points& normals, int k, bool reflect = false);

}  // namespace pointscale
