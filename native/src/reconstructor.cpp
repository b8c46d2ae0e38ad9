#include "pointscale/reconstructor.h"

#include <numeric>

#include "pointscale/parallel.h"
#include "pointscale/spatial_order.h"
#include "pointscale/detail/cluster_layout.h"
#include "pointscale/detail/reconstruct_levels.h"
#include "pointscale/validation.h"

namespace pointscale {

Reconstructor::Reconstructor(const MultiscaleModel& model) {
  validate(model);
  const Eigen::Index n = model.base.rows();
  const int k = model.bands();
  // Level 0's layout (cluster_layout.h): a spatial order, so level 0's fits read and write
  // consecutive rows.
  if (k > 0) {
    order_ = cluster_layout(model.support[0].labels, model.support[0].clusters).members;
  } else {
    order_.resize(static_cast<std::size_t>(n));
    std::iota(order_.begin(), order_.end(), 0);
  }
  const IndexList rank = inverse_order(order_);

  model_.base.resize(n, 3);
  model_.base_normals.resize(n, 3);
  model_.details.resize(k, n);
  parallel_for(static_cast<std::size_t>(n), [&](std::size_t b, std::size_t e) {
    for (std::size_t r = b; r < e; ++r) {
      const Eigen::Index i = order_[r], row = static_cast<Eigen::Index>(r);
      model_.base.row(row) = model.base.row(i);
      model_.base_normals.row(row) = model.base_normals.row(i);
      model_.details.col(row) = model.details.col(i);
    }
  }, {}, 4096);

  // What an edit needs, found in the model's own numbering (so that rings with neighbours at
  // equal distances list them as reconstruct() does), then renumbered.
  {
    const EditSupport from = edit_support(model);
    EditSupport& to = workspace_.edit;
    const std::size_t ring = static_cast<std::size_t>(from.ring_size);
    to.ring_size = from.ring_size;
    to.rings.resize(from.rings.size());
    to.feet.resize(from.feet.size());
    to.planes.normals.resize(from.planes.normals.size());
    to.planes.kind.resize(from.planes.kind.size());
    parallel_for(static_cast<std::size_t>(n), [&](std::size_t b, std::size_t e) {
      for (std::size_t r = b; r < e; ++r) {
        const std::size_t i = static_cast<std::size_t>(order_[r]);
        for (std::size_t j = 0; j < ring; ++j) to.rings[r * ring + j] = rank[from.rings[i * ring + j]];
        to.feet[r] = rank[from.feet[i]];
        to.planes.normals[r] = from.planes.normals[i];
        to.planes.kind[r] = from.planes.kind[i];
      }
    }, {}, 4096);
  }

  model_.support.resize(static_cast<std::size_t>(k));
  workspace_.groups.resize(static_cast<std::size_t>(k));
  for (int l = 0; l < k; ++l) {
    const LevelSupport& from = model.support[l];
    LevelSupport& to = model_.support[l];
    to.clusters = from.clusters;
    to.neighbors = from.neighbors;
    to.neighborhoods = from.neighborhoods;
    to.h = from.h;
    to.frames = from.frames;
    to.local = from.local;  // laid out by cluster_layout.h, which the renumbering below keeps
    to.labels.resize(from.labels.size());
    to.anchors.resize(from.anchors.size());
    for (std::size_t c = 0; c < from.anchors.size(); ++c) to.anchors[c] = rank[from.anchors[c]];
    // The layout (cluster_layout.h) with its members renumbered: each cluster's members stay in
    // the order support.local and reconstruct() take them in, so every fit is the same.
    LabelGroups groups = cluster_layout(from.labels, from.clusters);
    parallel_for(order_.size(), [&](std::size_t b, std::size_t e) {
      for (std::size_t r = b; r < e; ++r) {
        to.labels[r] = from.labels[order_[r]];
        groups.members[r] = rank[groups.members[r]];
      }
    }, {}, 16384);
    workspace_.groups[l] = std::move(groups);
  }
}

Points Reconstructor::reconstruct(const Eigen::MatrixXd& gains, const double* base, const Vec3& origin,
                                  const ProgressCallback* progress) {
  check_gains(gains, bands(), points());
  if (base) check_base(Eigen::Map<const Points>(base, points(), 3), points(), origin);
  const std::lock_guard<std::mutex> lock(busy_);
  const Eigen::Index n = points();
  const bool edited = base != nullptr;
  if (edited) {
    level_.resize(n, 3);
    parallel_for(static_cast<std::size_t>(n), [&](std::size_t b, std::size_t e) {
      for (std::size_t r = b; r < e; ++r)
        for (int a = 0; a < 3; ++a) level_(static_cast<Eigen::Index>(r), a) = base[3 * std::size_t(order_[r]) + a] - origin(a);
    }, {}, 4096);
  } else {
    level_ = model_.base;
  }
  const Eigen::MatrixXd* g = &gains;
  if (gains.cols() > 1) {
    gains_.resize(gains.rows(), n);
    parallel_for(static_cast<std::size_t>(n), [&](std::size_t b, std::size_t e) {
      for (std::size_t r = b; r < e; ++r) gains_.col(static_cast<Eigen::Index>(r)) = gains.col(order_[r]);
    }, {}, 4096);
    g = &gains_;
  }
  reconstruct_levels_in_place(model_, *g, level_, edited, nullptr, -1, progress, &workspace_);
  Points out(n, 3);
  const Eigen::RowVector3d shift = origin.transpose();
  parallel_for(static_cast<std::size_t>(n), [&](std::size_t b, std::size_t e) {
    for (std::size_t r = b; r < e; ++r) out.row(order_[r]) = level_.row(static_cast<Eigen::Index>(r)) + shift;
  }, {}, 4096);
  return out;
}

}  // namespace pointscale
