#include "pointscale/detail/level_orientation.h"

#include <algorithm>
#include <numeric>
#include <vector>

#include "pointscale/normal_estimation.h"
#include "pointscale/spatial_index.h"
#include "pointscale/detail/level_normals.h"

namespace pointscale {

Points oriented_anchor_normals(const Points& anchors, const LevelSupport& support) {
  std::vector<Index> own(static_cast<std::size_t>(support.clusters));
  std::iota(own.begin(), own.end(), 0);
  Points normals = support_normals(anchors, own.data(), anchors, support, Points::Zero(support.clusters, 3));
  orient_normals(SpatialIndex(anchors), normals, std::min<int>(16, support.clusters));
  return normals;
}

Points orientation_reference(const Points& level, const LevelSupport& support) {
  const Points cn = oriented_anchor_normals(support_centroids(level, support), support);
  Points reference(level.rows(), 3);
  for (Eigen::Index i = 0; i < level.rows(); ++i) reference.row(i) = cn.row(support.labels[i]);
  return reference;
}

}  // namespace pointscale
