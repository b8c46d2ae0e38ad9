// The k nearest points of a query with Gaussian weights whose kernel is the farthest one's
// distance: the nearest dominate, and a coincident one wins. Shared by knn_interpolate and the
// morph's sheet matching, so both weigh a neighbourhood alike (the sheet matching falls back to
// knn_interpolate's mean bit for bit).
#pragma once
#include <algorithm>

#include "pointscale/spatial_index.h"
#include "pointscale/detail/plane_fit.h"

namespace pointscale {

// query  3 coordinates
// idx, d2, inv_h2, w  each at least k long: the neighbours, their squared distances, the
//                     kernel (1 / h^2, one value) and the weights
// Returns how many were found (at most k, at least 1 for a non-empty index).
inline int knn_gaussian_weights(const SpatialIndex& index, const double* query, int k, Index* idx, double* d2,
                                double* inv_h2, double* w) {
  const int found = index.knn(query, k, idx, d2);
  const double h2 = std::max(d2[found - 1], 1e-300);
  std::fill(inv_h2, inv_h2 + found, 1.0 / h2);
  gaussian_weights(d2, inv_h2, found, w);
  return found;
}

}  // namespace pointscale
