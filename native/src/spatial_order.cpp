#include "pointscale/spatial_order.h"

#include <algorithm>
#include <cstdint>
#include <utility>
#include <vector>

#include "pointscale/parallel.h"

namespace pointscale {

namespace {

// Spreads the low 21 bits of v so that two zero bits follow each.
std::uint64_t spread_bits(std::uint64_t v) {
  v &= 0x1fffff;
  v = (v | v << 32) & 0x1f00000000ffffULL;
  v = (v | v << 16) & 0x1f0000ff0000ffULL;
  v = (v | v << 8) & 0x100f00f00f00f00fULL;
  v = (v | v << 4) & 0x10c30c30c30c30c3ULL;
  v = (v | v << 2) & 0x1249249249249249ULL;
  return v;
}

}  // namespace

IndexList morton_order(const Points& points) {
  const Eigen::Index n = points.rows();
  IndexList order(static_cast<std::size_t>(n));
  if (n == 0) return order;
  const Vec3 lo = points.colwise().minCoeff().transpose();
  const double extent = (points.colwise().maxCoeff().transpose() - lo).maxCoeff();
  const double scale = extent > 0 ? (double((1 << 21) - 1)) / extent : 0.0;
  std::vector<std::pair<std::uint64_t, Index>> keyed(static_cast<std::size_t>(n));
  for (Eigen::Index i = 0; i < n; ++i) {
    std::uint64_t key = 0;
    for (int a = 0; a < 3; ++a) {
      const double cell = (points(i, a) - lo(a)) * scale;
      key |= spread_bits(static_cast<std::uint64_t>(cell > 0 ? cell : 0.0)) << a;
    }
    keyed[static_cast<std::size_t>(i)] = {key, static_cast<Index>(i)};
  }
  std::sort(keyed.begin(), keyed.end());
  for (std::size_t i = 0; i < keyed.size(); ++i) order[i] = keyed[i].second;
  return order;
}

IndexList inverse_order(const IndexList& order) {
  IndexList out(order.size());
  parallel_for(order.size(), [&](std::size_t b, std::size_t e) {
    for (std::size_t t = b; t < e; ++t) out[static_cast<std::size_t>(order[t])] = static_cast<Index>(t);
  }, {}, 16384);
  return out;
}

LabelGroups group_by_label(const Index* labels, std::size_t n, Index count, const Index* visit) {
  LabelGroups g;
  g.offsets.assign(static_cast<std::size_t>(count) + 1, 0);
  for (std::size_t i = 0; i < n; ++i) ++g.offsets[static_cast<std::size_t>(labels[i]) + 1];
  for (std::size_t c = 0; c < static_cast<std::size_t>(count); ++c) g.offsets[c + 1] += g.offsets[c];
  g.members.resize(n);
  std::vector<Index> next(g.offsets.begin(), g.offsets.end() - 1);
  for (std::size_t t = 0; t < n; ++t) {
    const Index i = visit ? visit[t] : static_cast<Index>(t);
    g.members[static_cast<std::size_t>(next[labels[i]]++)] = i;
  }
  return g;
}

}  // namespace pointscale
