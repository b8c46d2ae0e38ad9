#include "pointscale/reconstructor.h"

#include <atomic>
#include <numeric>

#include "pointscale/stored_base.h"
#include "pointscale/parallel.h"
#include "pointscale/spatial_order.h"
#include "pointscale/detail/cluster_layout.h"
#include "pointscale/detail/reconstruct_levels.h"
#include "pointscale/validation.h"

namespace pointscale {

struct Reconstructor::State {
  MultiscaleModel model;  // reordered: row r (column r of details) is point order[r]
  IndexList order;        // #P
  IndexList rank;         // #P: point i is row rank[i] (order's inverse)
  IndexList parts;        // the model's part labels in its own numbering, or empty
  ReconstructionWorkspace workspace;
  Points level;           // the level being built, reordered
  Eigen::MatrixXd gains;  // per-point gains, reordered

  // What an edit needs (EditSupport), found in the model's own numbering, so that rings with
  // neighbours at equal distances list them as reconstruct() does, then renumbered.
  void find_edit_support(const ProgressStage& progress);

  // unit_pass in this workspace's layout, so that its normals are reconstruct()'s bit for bit:
  // the finest level at unit gains; its level normals orient the calls at other gains
  // (ReconstructionWorkspace::unit_reference), kept from the first such pass on.
  Points unit_pass_keeping_reference(const ProgressStage& progress) {
    Points finest = unit_pass(model, progress, workspace);
    if (!workspace.unit_reference)
      workspace.unit_reference = std::make_shared<const std::vector<Points>>(workspace.unedited_normals);
    return finest;
  }
};

namespace {

// rows[order[r]] = reordered[r]: a reordered array back in the model's own numbering.
Points in_model_order(const Points& reordered, const IndexList& order) {
  Points out(reordered.rows(), 3);
  parallel_for(order.size(), [&](std::size_t b, std::size_t e) {
    for (std::size_t r = b; r < e; ++r) out.row(order[r]) = reordered.row(static_cast<Eigen::Index>(r));
  }, {}, 4096);
  return out;
}

}  // namespace

Reconstructor::~Reconstructor() = default;
Eigen::Index Reconstructor::points() const { return state_->model.base.rows(); }
int Reconstructor::bands() const { return state_->model.bands(); }

Reconstructor::Reconstructor(const MultiscaleModel& model) : state_(std::make_unique<State>()) {
  validate(model);
  MultiscaleModel& model_ = state_->model;
  IndexList& order_ = state_->order;
  ReconstructionWorkspace& workspace_ = state_->workspace;
  workspace_.kept = true;
  state_->parts = model.parts;
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
  state_->rank = inverse_order(order_);
  const IndexList& rank = state_->rank;

  model_.base.resize(n, 3);
  model_.base_normals.resize(n, 3);
  model_.details.resize(k, n);
  if (!model.parts.empty()) model_.parts.resize(static_cast<std::size_t>(n));  // read by mirrored_points
  parallel_for(static_cast<std::size_t>(n), [&](std::size_t b, std::size_t e) {
    for (std::size_t r = b; r < e; ++r) {
      const Eigen::Index i = order_[r], row = static_cast<Eigen::Index>(r);
      model_.base.row(row) = model.base.row(i);
      model_.base_normals.row(row) = model.base_normals.row(i);
      model_.details.col(row) = model.details.col(i);
      if (!model.parts.empty()) model_.parts[r] = model.parts[static_cast<std::size_t>(i)];
    }
  }, {}, 4096);

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

void Reconstructor::State::find_edit_support(const ProgressStage& progress) {
  const Eigen::Index n = model.base.rows();
  // The unedited finest level, as reconstruct() finds it: this model's level loop gives it bit
  // for bit, in this order. Its level normals are those of unit gains, kept for the edited calls
  // at those gains (the cache holds one set of gains' normals anyway).
  const Points finest = unit_pass_keeping_reference(progress.sub(0.0, 0.5));
  const EditSupport from = edit_support(in_model_order(model.base, order), parts,
                                        in_model_order(model.base_normals, order), in_model_order(finest, order));
  // Renumbered into a support of its own, which becomes the workspace's only once complete: a
  // call that fails on the way leaves none, and the next call finds it again.
  EditSupport to;
  const std::size_t ring = static_cast<std::size_t>(from.ring_size);
  to.ring_size = from.ring_size;
  to.rings.resize(from.rings.size());
  to.feet.resize(from.feet.size());
  to.planes.normals.resize(from.planes.normals.size());
  to.planes.kind.resize(from.planes.kind.size());
  to.planes.in_plane.resize(from.planes.in_plane.size());
  to.planes.tolerance = from.planes.tolerance;
  parallel_for(static_cast<std::size_t>(n), [&](std::size_t b, std::size_t e) {
    for (std::size_t r = b; r < e; ++r) {
      const std::size_t i = static_cast<std::size_t>(order[r]);
      for (std::size_t j = 0; j < ring; ++j) to.rings[r * ring + j] = rank[from.rings[i * ring + j]];
      to.feet[r] = rank[from.feet[i]];
      to.planes.normals[r] = from.planes.normals[i];
      to.planes.kind[r] = from.planes.kind[i];
      to.planes.in_plane[r] = from.planes.in_plane[i];
    }
  }, {}, 4096);
  workspace.edit = std::make_shared<const EditSupport>(std::move(to));
  progress.report(1.0);
}

Points Reconstructor::reconstruct(const Eigen::MatrixXd& gains, const double* base, const Vec3& origin,
                                  const ProgressCallback* progress) {
  check_gains(gains, bands(), points());
  if (base) check_base(Eigen::Map<const Points>(base, points(), 3), points(), origin);
  const std::lock_guard<std::mutex> lock(busy_);
  State& s = *state_;
  const Eigen::Index n = points();
  // A base handed back unchanged turns no detail (as in reconstruct()), and is recognised in
  // the caller's coordinates (stored_base.h).
  bool edited = base != nullptr && !is_stored_base(base, s.model.base, origin, s.order.data());
  if (edited) {
    s.level.resize(n, 3);
    std::atomic<bool> differs{false};
    parallel_for(static_cast<std::size_t>(n), [&](std::size_t b, std::size_t e) {
      bool here = false;
      for (std::size_t r = b; r < e; ++r)
        for (int a = 0; a < 3; ++a) {
          const Eigen::Index row = static_cast<Eigen::Index>(r);
          const double v = base[3 * std::size_t(s.order[r]) + a] - origin(a);
          s.level(row, a) = v;
          here = here || v != s.model.base(row, a);
        }
      if (here) differs.store(true, std::memory_order_relaxed);
    }, {}, 4096);
    edited = differs.load();  // else centred onto it by rounding
  }
  if (!edited) s.level = s.model.base;
  // The first edited call finds the edit support too, which costs about twice the levels: it
  // takes the first two thirds of the progress.
  const ProgressStage all{progress, 0.0, 1.0};
  ProgressStage levels = all;
  if (edited && s.model.bands() > 0 && !s.workspace.edit) {
    s.find_edit_support(all.sub(0.0, 2.0 / 3.0));
    levels = all.sub(2.0 / 3.0, 1.0);
  }
  // Gains other than 1 orient each level's normals by those at unit gains
  // (ReconstructionWorkspace::unit_reference), found once.
  if (!all_unit(gains) && s.model.bands() > 1 && !s.workspace.unit_reference) {
    s.unit_pass_keeping_reference(levels.sub(0.0, 0.5));
    levels = levels.sub(0.5, 1.0);
  }
  const Eigen::MatrixXd* g = &gains;
  if (gains.cols() > 1) {
    s.gains.resize(gains.rows(), n);
    parallel_for(static_cast<std::size_t>(n), [&](std::size_t b, std::size_t e) {
      for (std::size_t r = b; r < e; ++r) s.gains.col(static_cast<Eigen::Index>(r)) = gains.col(s.order[r]);
    }, {}, 4096);
    g = &s.gains;
  }
  reconstruct_levels_in_place(s.model, *g, s.level, edited, nullptr, -1, levels, s.workspace);
  // Written in the caller's order (read in the layout's): a fresh array is then filled page
  // by page.
  Points out(n, 3);
  const Eigen::RowVector3d shift = origin.transpose();
  parallel_for(static_cast<std::size_t>(n), [&](std::size_t b, std::size_t e) {
    for (std::size_t i = b; i < e; ++i)
      out.row(static_cast<Eigen::Index>(i)) = s.level.row(s.rank[i]) + shift;
  }, {}, 4096);
  return out;
}

}  // namespace pointscale
