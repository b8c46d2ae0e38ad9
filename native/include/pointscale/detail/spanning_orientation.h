// Consistent orientation of unoriented normals along a minimum spanning tree of a
// k-nearest-neighbour graph (Hoppe et al. 1992), built by Kruskal's algorithm.
#pragma once
#include "pointscale/types.h"

namespace pointscale {

// points   #P by 3
// normals  #P by 3 unit normals, sign arbitrary; rows are flipped in place
// rows     #P by width row-major: each point's nearest points (itself may be among them), as
//          knn_graph gives them; taken, and freed as soon as the graph's edges are sorted
// Along the spanning forest of the graph (edges found from either side) that minimises the sum
// of 1 - |n_i . n_j|, each normal takes its tree neighbour's side. Each connected piece then
// turns outward by a vote of all its points, sum of n_i . (p_i - centroid of all points): the
// point farthest from the centroid alone is often an outlier whose normal lies nearly in the
// tangent plane. Closed shapes end up with outward normals.
// reflect  weigh and sign each edge by the reflected normal (angle_sorted_edges)
void orient_along_spanning_tree(const Points& points, Points& normals, IndexList&& rows, int width,
                                bool reflect = false);

}  // namespace pointscale
