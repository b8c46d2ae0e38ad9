#include "pointscale/detail/base_normals.h"

#include <algorithm>

#include "pointscale/normal_estimation.h"
#include "pointscale/parallel.h"

namespace pointscale {

Points oriented_normals(const SpatialIndex& base) {
  const int k = std::min<int>(16, base.size());
  Points normals = pca_normals(base, k);
  orient_normals(base, normals, k);
  return normals;
}

Points nearest_normals(const Points& query, const SpatialIndex& base, const Points& base_normals) {
  Points out(query.rows(), 3);
  parallel_for(static_cast<std::size_t>(query.rows()), [&](std::size_t b, std::size_t e) {
    Index nearest;
    double d2;
    for (std::size_t ii = b; ii < e; ++ii) {
      const Eigen::Index i = static_cast<Eigen::Index>(ii);
      base.knn(query.row(i).data(), 1, &nearest, &d2);
      out.row(i) = base_normals.row(nearest);
    }
  }, {}, 1024);
  return out;
}

}  // namespace pointscale
