#include "pointscale/sample_spacing.h"

#include <algorithm>
#include <cmath>

#include "pointscale/parallel.h"

namespace pointscale {

Eigen::VectorXd local_spacing(const SpatialIndex& index, int k) {
  const Index n = index.size();
  Eigen::VectorXd spacing(n);
  const int query = std::min<int>(n, k + 8);  // a few extra to step over duplicates
  parallel_for(static_cast<std::size_t>(n), [&](std::size_t b, std::size_t e) {
    std::vector<Index> idx(query);
    std::vector<double> d2(query);
    for (std::size_t i = b; i < e; ++i) {
      int found = index.knn(index.points().row(static_cast<Eigen::Index>(i)).data(), query, idx.data(), d2.data());
      double sum = 0.0;
      int used = 0;
      for (int j = 0; j < found && used < k; ++j)
        if (d2[j] > 0.0) { sum += std::sqrt(d2[j]); ++used; }
      spacing(static_cast<Eigen::Index>(i)) = used ? sum / used : 0.0;
    }
  });
  std::vector<double> positive;
  for (Index i = 0; i < n; ++i) if (spacing(i) > 0.0) positive.push_back(spacing(i));
  if (!positive.empty()) {
    std::nth_element(positive.begin(), positive.begin() + positive.size() / 2, positive.end());
    const double median = positive[positive.size() / 2];
    for (Index i = 0; i < n; ++i) if (!(spacing(i) > 0.0)) spacing(i) = median;
  }
  return spacing;
}

}  // namespace pointscale
