#include "pointscale/connected_parts.h"

#include <algorithm>
#include <numeric>
#include <stdexcept>

#include "pointscale/parallel.h"
#include "pointscale/spatial_index.h"
#include "pointscale/validation.h"

namespace pointscale {

namespace {

Index root(IndexList& parent, Index i) {
  while (parent[static_cast<std::size_t>(i)] != i) {
    Index& up = parent[static_cast<std::size_t>(i)];
    up = parent[static_cast<std::size_t>(up)];  // path halving keeps the trees shallow
    i = up;
  }
  return i;
}

}  // namespace

Parts connected_parts(const Points& points, const IndexList& pairs) {
  const Index n = static_cast<Index>(points.rows());
  if (pairs.size() % 2 != 0) throw std::invalid_argument("connectivity pairs must come two indices at a time");
  for (Index v : pairs)
    if (v < 0 || v >= n) throw std::invalid_argument("connectivity refers to a vertex out of range");
  IndexList parent(static_cast<std::size_t>(n));
  std::iota(parent.begin(), parent.end(), 0);
  std::vector<unsigned char> paired(static_cast<std::size_t>(n), 0);
  for (std::size_t e = 0; e < pairs.size(); e += 2) {
    const Index a = root(parent, pairs[e]), b = root(parent, pairs[e + 1]);
    paired[static_cast<std::size_t>(pairs[e])] = paired[static_cast<std::size_t>(pairs[e + 1])] = 1;
    if (a != b) parent[static_cast<std::size_t>(std::max(a, b))] = std::min(a, b);  // the lower index is the root
  }
  Parts out;
  out.labels.assign(static_cast<std::size_t>(n), -1);
  IndexList members;  // the paired vertices, for the loose ones to search
  IndexList part_of_root(static_cast<std::size_t>(n), -1);
  for (Index i = 0; i < n; ++i) {
    if (!paired[static_cast<std::size_t>(i)]) continue;
    const Index r = root(parent, i);
    Index& label = part_of_root[static_cast<std::size_t>(r)];
    if (label < 0) label = out.count++;
    out.labels[static_cast<std::size_t>(i)] = label;
    members.push_back(i);
  }
  if (members.empty()) {
    out.labels.assign(static_cast<std::size_t>(n), 0);
    out.count = n > 0 ? 1 : 0;
    return out;
  }
  if (members.size() == static_cast<std::size_t>(n)) return out;
  Points paired_points(static_cast<Eigen::Index>(members.size()), 3);
  for (std::size_t j = 0; j < members.size(); ++j) paired_points.row(static_cast<Eigen::Index>(j)) = points.row(members[j]);
  const SpatialIndex index(paired_points);
  parallel_for(static_cast<std::size_t>(n), [&](std::size_t b, std::size_t e) {
    for (std::size_t i = b; i < e; ++i) {
      if (paired[i]) continue;
      Index nearest = 0;
      double d2 = 0.0;
      index.knn(points.row(static_cast<Eigen::Index>(i)).data(), 1, &nearest, &d2);
      out.labels[i] = out.labels[static_cast<std::size_t>(members[static_cast<std::size_t>(nearest)])];
    }
  }, {}, 1024);
  return out;
}

IndexList knn_within_parts(const Points& points, const IndexList& parts, int k) {
  check_parts(parts, points.rows(), k);
  const std::size_t width = static_cast<std::size_t>(k);
  IndexList out(static_cast<std::size_t>(points.rows()) * width);
  if (parts.empty()) return out;
  const Index count = *std::max_element(parts.begin(), parts.end()) + 1;
  std::vector<IndexList> members(static_cast<std::size_t>(count));
  for (std::size_t i = 0; i < parts.size(); ++i) members[static_cast<std::size_t>(parts[i])].push_back(static_cast<Index>(i));
  for (const IndexList& part : members) {
    if (part.empty()) continue;
    Points own(static_cast<Eigen::Index>(part.size()), 3);
    for (std::size_t j = 0; j < part.size(); ++j) own.row(static_cast<Eigen::Index>(j)) = points.row(part[j]);
    const int found = std::min<int>(k, static_cast<int>(part.size()));
    const IndexList local = knn_graph(SpatialIndex(own), found);
    for (std::size_t j = 0; j < part.size(); ++j) {
      Index* row = out.data() + static_cast<std::size_t>(part[j]) * width;
      for (std::size_t m = 0; m < width; ++m)
        row[m] = m < static_cast<std::size_t>(found) ? part[static_cast<std::size_t>(local[j * static_cast<std::size_t>(found) + m])]
                                                     : part[j];
    }
  }
  return out;
}

}  // namespace pointscale
