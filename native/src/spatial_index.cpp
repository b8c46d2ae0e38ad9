#include "pointscale/spatial_index.h"

#include <nanoflann.hpp>
#include <utility>

#include "pointscale/parallel.h"
#include "pointscale/self_knn.h"

namespace pointscale {

namespace {

struct PointsAdaptor {
  const Points* points;
  inline std::size_t kdtree_get_point_count() const { return static_cast<std::size_t>(points->rows()); }
  inline double kdtree_get_pt(std::size_t i, std::size_t dim) const { return (*points)(static_cast<Eigen::Index>(i), static_cast<Eigen::Index>(dim)); }
  template <class BBox>
  bool kdtree_get_bbox(BBox&) const { return false; }
};

using Tree = nanoflann::KDTreeSingleIndexAdaptor<nanoflann::L2_Simple_Adaptor<double, PointsAdaptor>,
                                                 PointsAdaptor, 3, std::uint32_t>;

nanoflann::KDTreeSingleIndexAdaptorParams tree_params() {
#if defined(NANOFLANN_VERSION) && NANOFLANN_VERSION >= 0x151
  // 1.5.1+ can build the tree on several threads.
  return nanoflann::KDTreeSingleIndexAdaptorParams(16, nanoflann::KDTreeSingleIndexAdaptorFlags::None,
                                                   static_cast<unsigned int>(thread_count()));
#else
  return nanoflann::KDTreeSingleIndexAdaptorParams(16);
#endif
}

}  // namespace

struct SpatialIndex::Impl {
  Points points;
  PointsAdaptor adaptor;
  std::unique_ptr<Tree> tree;
  explicit Impl(const Points& p) : Impl(Points(p)) {}
  explicit Impl(Points&& p) : points(std::move(p)), adaptor{&points} {
    tree = std::make_unique<Tree>(3, adaptor, tree_params());
#if !defined(NANOFLANN_VERSION) || NANOFLANN_VERSION < 0x150
    // Some releases before 1.5 build the tree in the constructor (bookworm's 1.4.3 does),
    // older ones do not; build it only if it is not there, never twice.
    if (!tree->root_node) tree->buildIndex();
#endif
  }
};

SpatialIndex::SpatialIndex(const Points& points) : impl_(std::make_unique<Impl>(points)) {}
SpatialIndex::SpatialIndex(Points&& points) : impl_(std::make_unique<Impl>(std::move(points))) {}
SpatialIndex::~SpatialIndex() = default;
SpatialIndex::SpatialIndex(SpatialIndex&&) noexcept = default;
SpatialIndex& SpatialIndex::operator=(SpatialIndex&&) noexcept = default;

int SpatialIndex::knn(const double* query, int k, Index* indices, double* squared_distances) const {
  k = std::min<int>(k, static_cast<int>(impl_->points.rows()));
  if (k <= 0) return 0;
  std::uint32_t idx[256];
  std::vector<std::uint32_t> big;
  std::uint32_t* out = idx;
  if (k > 256) { big.resize(k); out = big.data(); }
  nanoflann::KNNResultSet<double, std::uint32_t> result(static_cast<std::size_t>(k));
  result.init(out, squared_distances);
#if defined(NANOFLANN_VERSION) && NANOFLANN_VERSION >= 0x150
  impl_->tree->findNeighbors(result, query, nanoflann::SearchParameters());
#else
  impl_->tree->findNeighbors(result, query, nanoflann::SearchParams());
#endif
  const int found = static_cast<int>(result.size());
  for (int i = 0; i < found; ++i) indices[i] = static_cast<Index>(out[i]);
  return found;
}

Index SpatialIndex::size() const { return static_cast<Index>(impl_->points.rows()); }
const Points& SpatialIndex::points() const { return impl_->points; }

IndexList knn_graph(const SpatialIndex& index, int k, const ProgressStage& stage) {
  const Index n = index.size();
  k = std::min<int>(k, n);
  IndexList out(static_cast<std::size_t>(n) * k);
  self_knn(index, k, [&](Index i, const Index* nearest, const double*, int found) {
    Index* row = out.data() + static_cast<std::size_t>(i) * k;
    std::copy(nearest, nearest + found, row);
    // Put the point itself first even among duplicates, so row i always starts with i.
    for (int j = 0; j < found; ++j)
      if (row[j] == i) { std::swap(row[0], row[j]); break; }
    if (found > 0 && row[0] != i) row[0] = i;
  }, stage);
  return out;
}

}  // namespace pointscale
