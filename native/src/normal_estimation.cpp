#include "pointscale/normal_estimation.h"

#include <algorithm>

#include "pointscale/detail/plane_fit.h"
#include "pointscale/self_knn.h"
#include "pointscale/detail/spanning_orientation.h"

namespace pointscale {

Points pca_normals(const SpatialIndex& index, int k, int width, IndexList& rows, const ProgressStage& stage) {
  const Index n = index.size();
  k = std::min<int>(k, n);
  width = std::max(0, std::min(width, k));
  rows.assign(static_cast<std::size_t>(n) * width, 0);
  Points normals = Points::Zero(n, 3);  // rows stay zero only when k < 1
  const Points& p = index.points();
  std::vector<double> w(static_cast<std::size_t>(k), 1.0);
  self_knn(index, k, [&](Index i, const Index* idx, const double*, int found) {
    const PlaneFit fit = fit_weighted_plane(p, idx, w.data(), found, p.row(i).transpose());
    normals.row(i) = (fit.ok ? fit.normal : Vec3(Vec3::Zero())).transpose();
    // found == k: the index holds at least k points. The nearest come first.
    std::copy(idx, idx + std::min(width, found), rows.data() + static_cast<std::size_t>(i) * width);
  }, stage);
  return normals;
}

Points pca_normals(const SpatialIndex& index, int k, const ProgressStage& stage) {
  IndexList none;
  return pca_normals(index, k, 0, none, stage);
}

void orient_normals(const SpatialIndex& index, Points& normals, int k, bool reflect) {
  const Index n = index.size();
  if (n == 0) return;
  IndexList graph = knn_graph(index, k);
  k = static_cast<int>(graph.size() / n);
  orient_along_spanning_tree(index.points(), normals, std::move(graph), k, reflect);
}

}  // namespace pointscale
