#include "pointscale/detail/thin_sheets.h"

#include <algorithm>

#include "pointscale/self_knn.h"

namespace pointscale {

Points cluster_side_normals(const Points& point_normals, const IndexList& labels, Index clusters) {
  Points sides = Points::Zero(clusters, 3);
  for (std::size_t i = 0; i < labels.size(); ++i) sides.row(labels[i]) += point_normals.row(static_cast<Eigen::Index>(i));
  for (Index c = 0; c < clusters; ++c) {
    const double length = sides.row(c).norm();
    if (length > 1e-9) sides.row(c) /= length;
    else sides.row(c).setZero();
  }
  return sides;
}

IndexList same_side_knn_graph(const SpatialIndex& index, const Points& side_normals, int k) {
  const Index n = index.size();
  k = std::min<int>(k, n);
  const int asked = std::min<int>(4 * k, n);
  IndexList out(static_cast<std::size_t>(n) * k);
  self_knn(index, asked, [&](Index i, const Index* nearest, const double*, int found) {
    Index* row = out.data() + static_cast<std::size_t>(i) * k;
    int filled = 0;
    row[filled++] = i;
    const auto side = side_normals.row(i);
    for (int j = 0; j < found && filled < k; ++j)
      if (nearest[j] != i && same_side(side.dot(side_normals.row(nearest[j])))) row[filled++] = nearest[j];
    for (int j = 0; j < found && filled < k; ++j)
      if (nearest[j] != i && !(same_side(side.dot(side_normals.row(nearest[j]))))) row[filled++] = nearest[j];
    while (filled < k) row[filled++] = i;
  });
  return out;
}

}  // namespace pointscale
