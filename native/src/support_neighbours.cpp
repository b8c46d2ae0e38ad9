#include "pointscale/support_neighbours.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include "pointscale/parallel.h"
#include "pointscale/sample_spacing.h"

namespace pointscale {

SupportNeighbours support_neighbours(const SpatialIndex& index, int width, int spacing_k, Eigen::VectorXd* spacing) {
  const Index n = index.size();
  SupportNeighbours out;
  out.width = std::max(0, std::min<int>(width, n));
  out.nearest.resize(static_cast<std::size_t>(n) * out.width);
  out.reach.resize(n);
  if (spacing) spacing->resize(n);
  const int w = out.width;
  const int spacing_query = std::min<int>(w, spacing_k + 8);
  parallel_for(static_cast<std::size_t>(n), [&](std::size_t b, std::size_t e) {
    std::vector<double> d2(static_cast<std::size_t>(w));
    for (std::size_t i = b; i < e; ++i) {
      Index* row = out.nearest.data() + i * w;
      const int found = index.knn(index.points().row(static_cast<Eigen::Index>(i)).data(), w, row, d2.data());
      out.reach(static_cast<Eigen::Index>(i)) = w == n ? std::numeric_limits<double>::infinity() : std::sqrt(d2[found - 1]);
      if (spacing) (*spacing)(static_cast<Eigen::Index>(i)) = spacing_from_neighbours(d2.data(), std::min(found, spacing_query), spacing_k);
    }
  });
  if (spacing) fill_missing_spacing(*spacing);
  return out;
}

}  // namespace pointscale
