#include "pointscale/detail/coincident_points.h"

#include <algorithm>
#include <unordered_map>

#include "pointscale/parallel.h"

namespace pointscale {

std::vector<std::pair<Index, Index>> coincident_points(const Points& points, const LabelGroups& groups,
                                                       const Points* sides) {
  std::vector<std::pair<Index, Index>> copies;
  auto less = [&](Index a, Index b) {
    for (int c = 0; c < 3; ++c)
      if (points(a, c) != points(b, c)) return points(a, c) < points(b, c);
    if (sides)
      for (int c = 0; c < 3; ++c)
        if ((*sides)(a, c) != (*sides)(b, c)) return (*sides)(a, c) < (*sides)(b, c);
    return a < b;
  };
  auto same = [&](Index a, Index b) {
    return (points.row(a).array() == points.row(b).array()).all() &&
           (!sides || (sides->row(a).array() == sides->row(b).array()).all());
  };
  const std::size_t count = groups.offsets.empty() ? 0 : groups.offsets.size() - 1;
  constexpr std::size_t chunk = 4096;  // groups
  std::vector<std::vector<std::pair<Index, Index>>> found((count + chunk - 1) / chunk);
  parallel_for(count, [&](std::size_t b, std::size_t e) {
    std::vector<Index> sorted;
    auto& out = found[b / chunk];
    for (std::size_t g = b; g < e; ++g) {
      sorted.assign(groups.members.begin() + groups.offsets[g], groups.members.begin() + groups.offsets[g + 1]);
      std::sort(sorted.begin(), sorted.end(), less);
      // Equal points sort by index, so each run's first is the run's lowest index.
      for (std::size_t start = 0; start < sorted.size();) {
        std::size_t end = start + 1;
        for (; end < sorted.size() && same(sorted[start], sorted[end]); ++end) out.emplace_back(sorted[end], sorted[start]);
        start = end;
      }
    }
  }, {}, chunk);
  for (const auto& f : found) copies.insert(copies.end(), f.begin(), f.end());
  std::sort(copies.begin(), copies.end());
  return copies;
}

void unify_coincident(const std::vector<std::pair<Index, Index>>& copies, Points& a, Points& b) {
  for (const auto& [copy, first] : copies) {
    a.row(copy) = a.row(first);
    b.row(copy) = b.row(first);
  }
}

void unify_coincident(const std::vector<std::pair<Index, Index>>& copies, const IndexList& anchors, Points& level,
                      Points& normals, Eigen::MatrixXd::RowXpr details) {
  if (copies.empty()) return;
  std::unordered_map<Index, Index> source;  // a group's first -> its anchor, where one of the copies is
  {
    std::vector<unsigned char> is_anchor(static_cast<std::size_t>(level.rows()), 0);
    for (Index a : anchors) is_anchor[static_cast<std::size_t>(a)] = 1;
    for (const auto& [copy, first] : copies)
      if (is_anchor[static_cast<std::size_t>(copy)]) source[first] = copy;
  }
  auto take = [&](Index to, Index from) {
    level.row(to) = level.row(from);
    normals.row(to) = normals.row(from);
    details(to) = details(from);
  };
  for (const auto& [copy, first] : copies) {
    const auto found = source.find(first);
    const Index from = found == source.end() ? first : found->second;
    if (copy != from) take(copy, from);
    if (first != from) take(first, from);
  }
}

}  // namespace pointscale
