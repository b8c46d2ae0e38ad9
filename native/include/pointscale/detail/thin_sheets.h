// Two-sided thin sheets (a leaf, sheet metal, a wall scanned from both sides): walls thinner
// than a level's kernel, which isotropic weights average onto their middle. Given the points'
// oriented normals, decompose keeps each side apart at three places: the decimation splits a
// cluster that straddles a wall by side (cluster_decimation.h), the projection weighs support
// points by their distance along their own normal (mls_projection.h), and each level's
// normals are fitted to the clusters of the same side only (same_side_knn_graph below), a
// neighbourhood cached at decomposition time like a mesh's connectivity, so it holds however
// the base is edited later.
#pragma once
#include "pointscale/spatial_index.h"
#include "pointscale/types.h"

namespace pointscale {

// Two oriented normals face the same way unless they turn by more than 120 degrees: the far side
// of a wall faces the opposite way (-1), while a one-sided surface keeps its right-angled edges
// (0), which are smoothed as they would be without thin sheets.
constexpr double same_side_cosine = -0.5;
inline bool same_side(double cosine) { return cosine > same_side_cosine; }

// The side each cluster faces: the normalised mean of its points' oriented normals, or a zero
// row where they cancel (a cluster the decimation could not split by side).
// point_normals  #P by 3 oriented normals
// labels         #P cluster of each point, in [0, clusters)
// Returns #C by 3.
Points cluster_side_normals(const Points& point_normals, const IndexList& labels, Index clusters);

// Each point's k nearest points on the same side: those whose side normal faces its own way
// (same_side), among its 4k nearest, itself first. Where fewer than k agree there, the row is
// filled with the nearest of the others, so that every row has k entries as knn_graph's do.
// index         the #C points (cluster anchors or centroids)
// side_normals  #C by 3 from cluster_side_normals
// Returns #C by k (k clipped to #C).
IndexList same_side_knn_graph(const SpatialIndex& index, const Points& side_normals, int k);

}  // namespace pointscale
