// k-nearest-neighbour queries on a fixed point set. nanoflann stays behind this interface.
#pragma once
#include <memory>

#include "pointscale/progress.h"
#include "pointscale/types.h"

namespace pointscale {

class SpatialIndex {
 public:
  // points  #P by 3; copied, so the index owns what it searches.
  explicit SpatialIndex(const Points& points);
  // The same, taking the points instead of copying them.
  explicit SpatialIndex(Points&& points);
  ~SpatialIndex();
  SpatialIndex(SpatialIndex&&) noexcept;
  SpatialIndex& operator=(SpatialIndex&&) noexcept;

  // Writes the k nearest points to `query` (closest first): indices and squared distances.
  // Returns how many were found (min(k, size())). Thread-safe.
  int knn(const double* query, int k, Index* indices, double* squared_distances) const;
  Index size() const;
  const Points& points() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

// For every point of `points`, its k nearest neighbours in `points` itself (itself first).
// Returns #P by k row-major indices.
IndexList knn_graph(const SpatialIndex& index, int k, const ProgressStage& stage = {});

}  // namespace pointscale
