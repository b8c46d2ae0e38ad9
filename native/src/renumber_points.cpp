#include "pointscale/detail/renumber_points.h"

#include <vector>

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

// Value i of the strided sequence data[0], data[stride], ... moves to place to[i]. One sequence
// (a coordinate, a band) at a time through an #P buffer: the model is complete by now, and a
// copy of a whole n x 3 array here would set decompose's peak memory.
void scatter_values(double* data, Eigen::Index stride, const IndexList& to, std::vector<double>& buffer) {
  buffer.resize(to.size());
  parallel_for(to.size(), [&](std::size_t b, std::size_t e) {
    for (std::size_t i = b; i < e; ++i) buffer[static_cast<std::size_t>(to[i])] = data[static_cast<Eigen::Index>(i) * stride];
  }, {}, 4096);
  parallel_for(to.size(), [&](std::size_t b, std::size_t e) {
    for (std::size_t i = b; i < e; ++i) data[static_cast<Eigen::Index>(i) * stride] = buffer[i];
  }, {}, 4096);
}

}  // namespace

void renumber_model(MultiscaleModel& model, const IndexList& original) {
  std::vector<double> buffer;
  for (Points* rows : {&model.base, &model.base_normals})
    for (int a = 0; a < 3; ++a) scatter_values(rows->data() + a, 3, original, buffer);
  const Eigen::Index bands = model.details.rows();  // column-major: band l is strided by `bands`
  for (Eigen::Index l = 0; l < bands; ++l) scatter_values(model.details.data() + l, bands, original, buffer);
  // Labels and anchors; the frame coordinates stay as they are (see the header).
  for (LevelSupport& s : model.support) {
    IndexList labels(original.size());
    for (std::size_t i = 0; i < original.size(); ++i) labels[static_cast<std::size_t>(original[i])] = s.labels[i];
    s.labels.swap(labels);
    for (Index& a : s.anchors) a = original[static_cast<std::size_t>(a)];
  }
}

}  // namespace pointscale
