// The one builder of a level's support (level_support.h) from a clustering of the level's
// points, behind decompose, encode_onto and decompose_rayshoot: labels, then anchors, then the
// anchors' neighbourhoods, kernel widths and frames.
#pragma once
#include "pointscale/detail/level_normals.h"

namespace pointscale {

// What differs between the callers, once the anchors are chosen.
struct LevelSupportRecipe {
  // #C kernel widths, given (decompose: from the decimated level's spacing), or nullptr for
  // kernel x the local spacing of the anchors.
  const Eigen::VectorXd* h = nullptr;
  double kernel = 1.0;
  // #C by 3 oriented cluster normals: each neighbourhood keeps to its cluster's side of a thin
  // sheet (same_side_knn_graph, thin_sheets.h). nullptr: plain k nearest.
  const Points* cluster_sides = nullptr;
  // The points grouped in the layout of cluster_layout.h, if the caller has them.
  const LabelGroups* groups = nullptr;
};

// labels #P, clusters #C; neighbours are capped at #C. The anchors come next (choose_anchors).
LevelSupport start_level_support(IndexList labels, Index clusters, int neighbors);

// The rest, once support.anchors is set. level #P by 3, the level's points.
void finish_level_support(const Points& level, LevelSupport& support, const LevelSupportRecipe& recipe);

// All of it: each cluster's anchor is its member of least |fine - level| (choose_anchors; rank
// breaks ties, see there). fine, level  #P by 3.
LevelSupport build_level_support(IndexList labels, Index clusters, const Points& fine, const Points& level,
                                 int neighbors, const LevelSupportRecipe& recipe, const Index* rank = nullptr);

}  // namespace pointscale
