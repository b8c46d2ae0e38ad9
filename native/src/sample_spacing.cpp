#include "pointscale/sample_spacing.h"

#include <algorithm>
#include <cmath>

#include "pointscale/self_knn.h"

namespace pointscale {

double spacing_from_neighbours(const double* squared_distances, int found, int k) {
  double sum = 0.0;
  int used = 0;
  for (int j = 0; j < found && used < k; ++j)
    if (squared_distances[j] > 0.0) { sum += std::sqrt(squared_distances[j]); ++used; }
  return used ? sum / used : 0.0;
}

void fill_missing_spacing(Eigen::VectorXd& spacing) {
  std::vector<double> positive;
  for (Eigen::Index i = 0; i < spacing.size(); ++i) if (spacing(i) > 0.0) positive.push_back(spacing(i));
  if (positive.empty()) return;
  std::nth_element(positive.begin(), positive.begin() + positive.size() / 2, positive.end());
  const double median = positive[positive.size() / 2];
  for (Eigen::Index i = 0; i < spacing.size(); ++i) if (!(spacing(i) > 0.0)) spacing(i) = median;
}

Eigen::VectorXd local_spacing(const SpatialIndex& index, int k) {
  const Index n = index.size();
  Eigen::VectorXd spacing(n);
  const int query = std::min<int>(n, k + 8);  // a few extra to step over duplicates
  self_knn(index, query, [&](Index i, const Index*, const double* d2, int found) {
    spacing(i) = spacing_from_neighbours(d2, found, k);
  });
  fill_missing_spacing(spacing);
  if (n > 0 && !(spacing(0) > 0.0)) {
    // Every point's nearest k + 8 are its own duplicates (a few positions, each repeated many
    // times): nothing to measure. Take the spacing of n points spread over the bounding box's
    // largest side instead of 0, which would give zero kernel widths (NaN weights).
    const Points& p = index.points();
    const double side = (p.colwise().maxCoeff() - p.colwise().minCoeff()).maxCoeff();
    spacing.setConstant(side / std::sqrt(static_cast<double>(n)));
  }
  return spacing;
}

}  // namespace pointscale
