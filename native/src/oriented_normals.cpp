#include "pointscale/oriented_normals.h"

#include <stdexcept>

#include "pointscale/validation.h"

#include <memory>
#include <utility>

#include "pointscale/normal_estimation.h"
#include "pointscale/parallel.h"
#include "pointscale/detail/renumber_points.h"
#include "pointscale/detail/spanning_orientation.h"
#include "pointscale/spatial_index.h"
#include "pointscale/spatial_order.h"

namespace pointscale {

Points oriented_normals(Points&& points, int k, int width) {
  check_normal_estimation(points, k);
  if (width < 1 || width > k) throw std::invalid_argument("width must be in [1, k]");
  const Index n = static_cast<Index>(points.rows());
  const IndexList order = morton_order(points);
  std::unique_ptr<SpatialIndex> index;
  {
    const Points input = std::move(points);
    index = std::make_unique<SpatialIndex>(gather_rows(input, order));
  }
  IndexList rows;
  Points normals = pca_normals(*index, k, width, rows);
  const int w = n > 0 ? static_cast<int>(rows.size() / static_cast<std::size_t>(n)) : 0;
  orient_along_spanning_tree(index->points(), normals, std::move(rows), w);
  index.reset();
  Points out(n, 3);
  parallel_for(static_cast<std::size_t>(n), [&](std::size_t b, std::size_t e) {
    for (std::size_t t = b; t < e; ++t) out.row(order[t]) = normals.row(static_cast<Eigen::Index>(t));
  }, {}, 4096);
  return out;
}

}  // namespace pointscale
