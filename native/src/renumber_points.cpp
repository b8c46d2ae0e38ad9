#include "pointscale/renumber_points.h"

#include "pointscale/parallel.h"

namespace pointscale {

Points gather_rows(const Points& rows, const IndexList& order) {
  Points out(static_cast<Eigen::Index>(order.size()), 3);
  parallel_for(order.size(), [&](std::size_t b, std::size_t e) {
    for (std::size_t t = b; t < e; ++t) out.row(static_cast<Eigen::Index>(t)) = rows.row(order[t]);
  }, {}, 4096);
  return out;
}

IndexList number_by_groups(Points& points, IndexList& labels, LabelGroups& groups) {
  IndexList original = std::move(groups.members);
  points = gather_rows(points, original);
  IndexList renumbered(original.size());
  for (std::size_t i = 0; i < original.size(); ++i) renumbered[i] = labels[static_cast<std::size_t>(original[i])];
  labels.swap(renumbered);
  groups.members.resize(original.size());
  for (std::size_t i = 0; i < original.size(); ++i) groups.members[i] = static_cast<Index>(i);
  return original;
}

namespace {

// Row i moves to row to[i].
void scatter_rows(Points& rows, const IndexList& to) {
  Points out(rows.rows(), 3);
  parallel_for(to.size(), [&](std::size_t b, std::size_t e) {
    for (std::size_t i = b; i < e; ++i) out.row(to[i]) = rows.row(static_cast<Eigen::Index>(i));
  }, {}, 4096);
  rows.swap(out);
}

}  // namespace

IndexList inverse_order(const IndexList& order) {
  IndexList out(order.size());
  for (std::size_t t = 0; t < order.size(); ++t) out[static_cast<std::size_t>(order[t])] = static_cast<Index>(t);
  return out;
}

void renumber_model(MultiscaleModel& model, const IndexList& original) {
  scatter_rows(model.base, original);
  scatter_rows(model.base_normals, original);
  Eigen::MatrixXd details(model.details.rows(), model.details.cols());
  parallel_for(original.size(), [&](std::size_t b, std::size_t e) {
    for (std::size_t i = b; i < e; ++i) details.col(original[i]) = model.details.col(static_cast<Eigen::Index>(i));
  }, {}, 4096);
  model.details.swap(details);
  // Labels and anchors; the frame coordinates stay as they are (see the header).
  for (LevelSupport& s : model.support) {
    IndexList labels(original.size());
    for (std::size_t i = 0; i < original.size(); ++i) labels[static_cast<std::size_t>(original[i])] = s.labels[i];
    s.labels.swap(labels);
    for (Index& a : s.anchors) a = original[static_cast<std::size_t>(a)];
  }
}

}  // namespace pointscale
