#include "pointscale/detail/level_orientation.h"

#include <algorithm>
#include <numeric>
#include <vector>

#include "pointscale/normal_estimation.h"
#include "pointscale/spatial_index.h"
#include "pointscale/detail/level_normals.h"
#include "pointscale/detail/spanning_orientation.h"

namespace pointscale {

Points anchor_normals(const Points& anchors, const LevelSupport& support) {
  std::vector<Index> own(static_cast<std::size_t>(support.clusters));
  std::iota(own.begin(), own.end(), 0);
  return support_normals(anchors, own.data(), anchors, support, Points::Zero(support.clusters, 3));
}

Points oriented_anchor_normals(const Points& anchors, const LevelSupport& support) {
  Points normals = anchor_normals(anchors, support);
  // The 12 nearest, as estimate_normals takes (a wider graph crosses thin parts sooner), each
  // edge weighed by the reflected normal, which tells a thin part's far side, whose normal
  // faces the other way, from agreement (angle_sorted_edges.h): on a 20k-point torus whose
  // tube is 3 anchors wide, the plain weight turned half of it inward.
  orient_normals(SpatialIndex(anchors), normals, std::min<int>(12, support.clusters), true);
  return normals;
}

void orient_cluster_normals(const Points& anchors, Points& normals, const LevelSupport& support) {
  const int width = std::min<int>(12, support.neighbors);
  IndexList rows(static_cast<std::size_t>(support.clusters) * width);
  for (Index c = 0; c < support.clusters; ++c)
    std::copy_n(support.neighborhoods.data() + static_cast<std::size_t>(c) * support.neighbors, width,
                rows.data() + static_cast<std::size_t>(c) * width);
  orient_along_spanning_tree(anchors, normals, std::move(rows), width, true);
}

Points orientation_reference(const Points& level, const LevelSupport& support) {
  const Points cn = oriented_anchor_normals(support_centroids(level, support), support);
  Points reference(level.rows(), 3);
  for (Eigen::Index i = 0; i < level.rows(); ++i) reference.row(i) = cn.row(support.labels[i]);
  return reference;
}

}  // namespace pointscale
