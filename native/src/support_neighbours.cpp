#include "pointscale/detail/support_neighbours.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include "pointscale/self_knn.h"
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
  if (w == 0) {  // no rows asked for: nothing bounds a query, and no spacing is known
    out.reach.setConstant(std::numeric_limits<double>::infinity());
    if (spacing) spacing->setZero();
    return out;
  }
  self_knn(index, w, [&](Index i, const Index* nearest, const double* d2, int found) {
    std::copy(nearest, nearest + found, out.nearest.data() + static_cast<std::size_t>(i) * w);
    out.reach(i) = w == n ? std::numeric_limits<double>::infinity() : std::sqrt(d2[found - 1]);
    if (spacing) (*spacing)(i) = spacing_from_neighbours(d2, std::min(found, spacing_query), spacing_k);
  });
  if (spacing) fill_missing_spacing(*spacing);
  return out;
}

}  // namespace pointscale
