#include "pointscale/detail/angle_sorted_edges.h"

#include <algorithm>
#include <cmath>

#include "pointscale/parallel.h"
#include "pointscale/detail/portable.h"

namespace pointscale {

namespace {

// Weights lie in [0, 1]: the top 16 bits of a float in that range run from 0 to 0x3F80, and
// they order non-negative floats as the floats do.
constexpr std::uint32_t key_count = 0x3F81;

std::uint32_t weight_key(double dot) {
  const float w = static_cast<float>(std::min(1.0, std::max(0.0, 1.0 - std::abs(dot))));
  return bit_cast<std::uint32_t>(w) >> 16;
}

}  // namespace

std::vector<SignedEdge> angle_sorted_edges(const IndexList& rows, int width, const Points& normals,
                                           const Points* points) {
  const std::size_t n = static_cast<std::size_t>(normals.rows());
  std::vector<SignedEdge> edges;
  if (n == 0 || width <= 0) return edges;
  // Fixed blocks of points, each with its own histogram: the order within a key is that of the
  // rows whatever the thread count, since blocks are contiguous and laid out in order.
  const std::size_t blocks = std::min<std::size_t>(n, 4 * static_cast<std::size_t>(thread_count()));
  const std::size_t per_block = (n + blocks - 1) / blocks;
  std::vector<std::size_t> slot(blocks * key_count, 0);

  // Calls emit(key, a, b_flip) for every edge whose first row is in [begin, end).
  auto each_edge = [&](std::size_t begin, std::size_t end, auto&& emit) {
    for (std::size_t i = begin; i < end; ++i) {
      const Index* row = rows.data() + i * width;
      const auto ni = normals.row(static_cast<Eigen::Index>(i));
      for (int s = 0; s < width; ++s) {
        const std::size_t j = static_cast<std::size_t>(row[s]);
        if (j == i) continue;
        if (j < i) {
          // Found from j's side too: that row emits it.
          const Index* other = rows.data() + j * width;
          if (std::find(other, other + width, static_cast<Index>(i)) != other + width) continue;
        }
        const double dot =
            points ? edge_agreement(ni, normals.row(static_cast<Eigen::Index>(j)), points->row(static_cast<Eigen::Index>(i)),
                                    points->row(static_cast<Eigen::Index>(j)), true)
                   : ni.dot(normals.row(static_cast<Eigen::Index>(j)));
        emit(weight_key(dot), static_cast<std::uint32_t>(i),
             static_cast<std::uint32_t>(j) | (dot < 0.0 ? 0x80000000u : 0u));
      }
    }
  };

  parallel_for(blocks, [&](std::size_t b0, std::size_t b1) {
    for (std::size_t b = b0; b < b1; ++b) {
      std::size_t* count = slot.data() + b * key_count;
      each_edge(b * per_block, std::min(n, (b + 1) * per_block),
                [&](std::uint32_t key, std::uint32_t, std::uint32_t) { ++count[key]; });
    }
  }, {}, 1);
  // Counts to starting slots: key by key, block by block within a key.
  std::size_t total = 0;
  for (std::uint32_t key = 0; key < key_count; ++key)
    for (std::size_t b = 0; b < blocks; ++b) {
      const std::size_t c = slot[b * key_count + key];
      slot[b * key_count + key] = total;
      total += c;
    }
  edges.resize(total);
  parallel_for(blocks, [&](std::size_t b0, std::size_t b1) {
    for (std::size_t b = b0; b < b1; ++b) {
      std::size_t* next = slot.data() + b * key_count;
      each_edge(b * per_block, std::min(n, (b + 1) * per_block),
                [&](std::uint32_t key, std::uint32_t a, std::uint32_t b_flip) { edges[next[key]++] = {a, b_flip}; });
    }
  }, {}, 1);
  return edges;
}

}  // namespace pointscale
