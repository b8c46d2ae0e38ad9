#include "pointscale/detail/build_level_support.h"

#include <algorithm>
#include <utility>

#include "pointscale/sample_spacing.h"
#include "pointscale/spatial_index.h"
#include "pointscale/detail/thin_sheets.h"
#include "pointscale/detail/level_normals.h"

namespace pointscale {

LevelSupport start_level_support(IndexList labels, Index clusters, int neighbors) {
  LevelSupport support;
  support.labels = std::move(labels);
  support.clusters = clusters;
  support.neighbors = std::min<int>(neighbors, clusters);
  return support;
}

void finish_level_support(const Points& level, LevelSupport& support, const LevelSupportRecipe& recipe) {
  const Points centroids = support_centroids(level, support);
  const SpatialIndex index(centroids);
  support.h = recipe.h ? *recipe.h : Eigen::VectorXd(recipe.kernel * local_spacing(index, 6));
  support.neighborhoods = recipe.cluster_sides ? same_side_knn_graph(index, *recipe.cluster_sides, support.neighbors)
                                               : knn_graph(index, support.neighbors);
  attach_frames(centroids, level, support, recipe.groups);
}

LevelSupport build_level_support(IndexList labels, Index clusters, const Points& fine, const Points& level,
                                 int neighbors, const LevelSupportRecipe& recipe, const Index* rank) {
  LevelSupport support = start_level_support(std::move(labels), clusters, neighbors);
  choose_anchors(fine, level, support, rank);
  finish_level_support(level, support, recipe);
  return support;
}

}  // namespace pointscale
