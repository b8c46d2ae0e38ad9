// Hierarchical-clustering decimation (Pauly et al. 2002; the paper's Sec. 5.2).
#pragma once
#include "pointscale/types.h"

namespace pointscale {

struct Clustering {
  Points centroids;  // #C by 3
  IndexList labels;  // #P, the cluster of each input point
};

// Splits clusters through their centroid, along the axis of largest covariance, largest cluster
// first, until there are `target` clusters; a cluster whose surface variation exceeds
// `max_variation` counts as four times its size, so curved regions get more, smaller clusters.
// Clusters of identical points cannot be split, so fewer than `target` may come back.
// points      #P by 3
// read_order  #P: the order in which the points are read, or nullptr for 0..#P-1. The splits sum
//             over the points in this order, so a caller that renumbers the points and passes
//             the old numbering's order gets the same clusters, bit for bit.
// side_normals #P by 3 oriented normals, or nullptr. With them, a cluster whose normals disagree
//             (both sides of a wall thinner than it) is first split by the side its points face,
//             so that no cluster, and no centroid, straddles a thin sheet.
// Throws std::invalid_argument for what check_decimation (validation.h) refuses.
Clustering cluster_decimate(const Points& points, std::size_t target, double max_variation = 0.05,
                            const IndexList* read_order = nullptr, const Points* side_normals = nullptr);

}  // namespace pointscale
