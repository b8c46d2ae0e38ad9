#include "pointscale/self_knn.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <vector>

#include "pointscale/parallel.h"

namespace pointscale {

namespace {

using Key = std::uint64_t;
constexpr int coordinate_bits = 21;
constexpr std::int64_t max_cells_per_axis = (std::int64_t{1} << coordinate_bits) - 2;

Key cell_key(std::int64_t x, std::int64_t y, std::int64_t z) {
  return (static_cast<Key>(x) << (2 * coordinate_bits)) | (static_cast<Key>(y) << coordinate_bits) | static_cast<Key>(z);
}

// The points sorted by cell, with an open-addressing table from a cell's key to its range.
struct Grid {
  double cell = 0;
  Vec3 origin;
  std::vector<Key> keys;            // per cell
  std::vector<std::uint32_t> start; // #cells + 1: the cell's range in ids/xyz
  std::vector<Index> ids;           // the points, cell by cell
  std::vector<double> x, y, z;      // their coordinates, in the same order
  std::vector<Key> table_key;
  std::vector<std::uint32_t> table_cell;
  std::uint64_t mask = 0;
  int shift = 60;

  // Fibonacci hashing: the product's top bits.
  std::uint64_t slot(Key key) const { return (key * 0x9E3779B97F4A7C15ull) >> shift; }
  // The cell of `key`, or -1 if it holds no point.
  std::int64_t find(Key key) const {
    for (std::uint64_t s = slot(key);; s = (s + 1) & mask) {
      if (table_cell[s] == std::numeric_limits<std::uint32_t>::max()) return -1;
      if (table_key[s] == key) return table_cell[s];
    }
  }
};

// Builds the grid, or returns false when the cloud is too large for the key's 21 bits a side.
// Cells are numbered in the order their first point comes (a counting sort through the hash
// table, so that the keys need no sort).
bool build_grid(const Points& p, double cell, Grid& g) {
  const Index n = static_cast<Index>(p.rows());
  g.cell = cell;
  g.origin = p.colwise().minCoeff().transpose();
  const Vec3 extent = p.colwise().maxCoeff().transpose() - g.origin;
  if (!(extent.maxCoeff() / cell < static_cast<double>(max_cells_per_axis))) return false;
  std::vector<Key> key_of(static_cast<std::size_t>(n));
  parallel_for(static_cast<std::size_t>(n), [&](std::size_t b, std::size_t e) {
    for (std::size_t i = b; i < e; ++i) {
      const auto q = p.row(static_cast<Eigen::Index>(i));
      const auto c = [&](int d) { return static_cast<std::int64_t>(std::floor((q(d) - g.origin(d)) / cell)); };
      key_of[i] = cell_key(c(0), c(1), c(2));
    }
  }, {}, 4096);
  // The table doubles whenever it is half full (cells hold several points each: a table for
  // one per point would cost more to clear than the rest of the build).
  std::vector<std::uint32_t> cell_of(static_cast<std::size_t>(n));
  std::vector<std::uint32_t> count;
  g.keys.clear();
  auto rehash = [&](std::size_t size) {
    g.shift = 64;
    for (std::size_t s = size; s > 1; s /= 2) --g.shift;
    g.mask = size - 1;
    g.table_key.assign(size, 0);
    g.table_cell.assign(size, std::numeric_limits<std::uint32_t>::max());
    for (std::size_t c = 0; c < g.keys.size(); ++c) {
      std::uint64_t s = g.slot(g.keys[c]);
      while (g.table_cell[s] != std::numeric_limits<std::uint32_t>::max()) s = (s + 1) & g.mask;
      g.table_key[s] = g.keys[c];
      g.table_cell[s] = static_cast<std::uint32_t>(c);
    }
  };
  rehash(1024);
  for (Index i = 0; i < n; ++i) {
    const Key key = key_of[static_cast<std::size_t>(i)];
    std::uint64_t s = g.slot(key);
    while (g.table_cell[s] != std::numeric_limits<std::uint32_t>::max() && g.table_key[s] != key) s = (s + 1) & g.mask;
    if (g.table_cell[s] == std::numeric_limits<std::uint32_t>::max()) {
      g.keys.push_back(key);
      count.push_back(0);
      if (2 * g.keys.size() > g.mask + 1) {
        rehash(2 * (g.mask + 1));
        s = g.slot(key);
        while (g.table_key[s] != key) s = (s + 1) & g.mask;
      } else {
        g.table_key[s] = key;
        g.table_cell[s] = static_cast<std::uint32_t>(g.keys.size() - 1);
      }
    }
    cell_of[static_cast<std::size_t>(i)] = g.table_cell[s];
    ++count[g.table_cell[s]];
  }
  g.start.assign(g.keys.size() + 1, 0);
  for (std::size_t c = 0; c < g.keys.size(); ++c) g.start[c + 1] = g.start[c] + count[c];
  std::vector<std::uint32_t> next(g.start.begin(), g.start.end() - 1);
  g.ids.resize(n);
  g.x.resize(n);
  g.y.resize(n);
  g.z.resize(n);
  for (Index i = 0; i < n; ++i) {
    const std::uint32_t j = next[cell_of[static_cast<std::size_t>(i)]]++;
    g.ids[j] = i;
    g.x[j] = p(i, 0);
    g.y[j] = p(i, 1);
    g.z[j] = p(i, 2);
  }
  return true;
}

// The cell width: 1.4 times the median k-th neighbour distance of a sample. Rows that end
// past the block of 27 cells around their point go to the tree; narrower cells send more
// there, wider ones give every query more candidates; this width leaves few rows to the tree on
// evenly and unevenly sampled surfaces alike.
double cell_width(const SpatialIndex& index, int k) {
  const Index n = index.size();
  const Index samples = std::min<Index>(n, 256);
  std::vector<double> reach;
  std::vector<Index> idx(static_cast<std::size_t>(k));
  std::vector<double> d2(static_cast<std::size_t>(k));
  for (Index s = 0; s < samples; ++s) {
    const Index i = static_cast<Index>(static_cast<std::int64_t>(s) * n / samples);
    const int found = index.knn(index.points().row(i).data(), k, idx.data(), d2.data());
    if (found == k && d2[k - 1] > 0) reach.push_back(std::sqrt(d2[k - 1]));
  }
  if (reach.empty()) return 0;
  std::nth_element(reach.begin(), reach.begin() + reach.size() / 2, reach.end());
  return 1.4 * reach[reach.size() / 2];
}

void tree_rows(const SpatialIndex& index, int k, const SelfKnnSink& emit, const ProgressStage& stage) {
  parallel_for(static_cast<std::size_t>(index.size()), [&](std::size_t b, std::size_t e) {
    std::vector<Index> idx(static_cast<std::size_t>(k));
    std::vector<double> d2(static_cast<std::size_t>(k));
    for (std::size_t i = b; i < e; ++i) {
      const int found = index.knn(index.points().row(static_cast<Eigen::Index>(i)).data(), k, idx.data(), d2.data());
      emit(static_cast<Index>(i), idx.data(), d2.data(), found);
    }
  }, stage);
}

}  // namespace

void self_knn(const SpatialIndex& index, int k, const SelfKnnSink& emit, const ProgressStage& stage) {
  const Index n = index.size();
  k = std::min<int>(k, n);
  if (k <= 0) return;
  // Small sets: the tree alone.
  if (n < 4096) return tree_rows(index, k, emit, stage);
  const Points& p = index.points();
  const double width = cell_width(index, k);
  Grid g;
  if (!(width > 0) || !build_grid(p, width, g)) return tree_rows(index, k, emit, stage);
  // Rounding in the cell assignment moves a point across a border by a few ulps of the
  // coordinates at most; the border distances are shortened by far more than that.
  const double slack = 1e-12 * (p.cwiseAbs().maxCoeff() + width);

  const std::size_t crowded = 32 * static_cast<std::size_t>(k) + 256;
  const std::size_t cells = g.keys.size();
  parallel_for(cells, [&](std::size_t b, std::size_t e) {
    std::vector<double> cx, cy, cz;
    std::vector<Index> cid;
    std::vector<double> dist, fd, sd;
    std::vector<Index> fi, si;
    std::vector<std::uint32_t> bucket, count;
    std::vector<Index> idx(static_cast<std::size_t>(k));
    std::vector<double> d2(static_cast<std::size_t>(k));
    for (std::size_t c = b; c < e; ++c) {
      const Key key = g.keys[c];
      const auto ix = static_cast<std::int64_t>(key >> (2 * coordinate_bits));
      const auto iy = static_cast<std::int64_t>((key >> coordinate_bits) & ((Key{1} << coordinate_bits) - 1));
      const auto iz = static_cast<std::int64_t>(key & ((Key{1} << coordinate_bits) - 1));
      cx.clear();
      cy.clear();
      cz.clear();
      cid.clear();
      for (std::int64_t dx = -1; dx <= 1; ++dx)
        for (std::int64_t dy = -1; dy <= 1; ++dy)
          for (std::int64_t dz = -1; dz <= 1; ++dz) {
            if (ix + dx < 0 || iy + dy < 0 || iz + dz < 0) continue;
            const std::int64_t other = g.find(cell_key(ix + dx, iy + dy, iz + dz));
            if (other < 0) continue;
            for (std::uint32_t j = g.start[other]; j < g.start[other + 1]; ++j) {
              cx.push_back(g.x[j]);
              cy.push_back(g.y[j]);
              cz.push_back(g.z[j]);
              cid.push_back(g.ids[j]);
            }
          }
      const std::size_t m = cid.size();
      // A block crowded far past what its width was chosen for (duplicates, a dense patch in
      // a sparse scan) would cost its points more than the tree does.
      if (m > static_cast<std::size_t>(crowded)) {
        for (std::uint32_t j = g.start[c]; j < g.start[c + 1]; ++j) {
          const int found = index.knn(p.row(g.ids[j]).data(), k, idx.data(), d2.data());
          emit(g.ids[j], idx.data(), d2.data(), found);
        }
        continue;
      }
      dist.resize(m);
      fd.resize(m);
      fi.resize(m);
      sd.resize(m);
      si.resize(m);
      bucket.resize(m);
      const bool block_holds_all = m == static_cast<std::size_t>(n);
      const Vec3 low = g.origin + g.cell * Vec3(ix - 1, iy - 1, iz - 1);
      const Vec3 high = g.origin + g.cell * Vec3(ix + 2, iy + 2, iz + 2);
      // The k-th distance of the cell's previous point bounds this one's: its k nearest lie
      // within that distance plus the step between the two (both are exact rows).
      double last_reach = -1, px = 0, py = 0, pz = 0;
      for (std::uint32_t j = g.start[c]; j < g.start[c + 1]; ++j) {
        const double qx = g.x[j], qy = g.y[j], qz = g.z[j];
        const Index self = g.ids[j];
        const double border = std::min({qx - low.x(), high.x() - qx, qy - low.y(), high.y() - qy, qz - low.z(), high.z() - qz}) - slack;
        // Rows end strictly inside the border: nothing outside the block is nearer.
        double keep = block_holds_all ? std::numeric_limits<double>::infinity()
                      : border > 0 ? std::nextafter(border * border, 0.0) : -1.0;
        if (last_reach >= 0) {
          const double step = std::sqrt((qx - px) * (qx - px) + (qy - py) * (qy - py) + (qz - pz) * (qz - pz));
          const double bound = (last_reach + step) * (last_reach + step) * (1 + 1e-12);
          keep = std::min(keep, bound);
        }
        double* dd = dist.data();
        for (std::size_t t = 0; t < m; ++t) {
          // The squared distance exactly as nanoflann's L2 adaptor sums it.
          const double dx = qx - cx[t], dy = qy - cy[t], dz = qz - cz[t];
          dd[t] = dx * dx + dy * dy + dz * dz;
        }
        std::size_t kept = 0;
        for (std::size_t t = 0; t < m; ++t) {
          fd[kept] = dd[t];
          fi[kept] = cid[t];
          kept += dd[t] <= keep;
        }
        px = qx; py = qy; pz = qz;
        if (kept < static_cast<std::size_t>(k)) {
          const int found = index.knn(p.row(self).data(), k, idx.data(), d2.data());
          emit(self, idx.data(), d2.data(), found);
          last_reach = -1;
          continue;
        }
        // Sorted by a counting sort on the squared distance's bucket (on a surface the kept
        // points spread about evenly over the buckets), then by an insertion sort, which has
        // only the ties within a bucket left to order.
        double largest = 0;
        for (std::size_t t = 0; t < kept; ++t) largest = std::max(largest, fd[t]);
        const std::size_t buckets = 2 * kept;
        const double per_bucket = largest > 0 ? static_cast<double>(buckets) / largest : 0.0;
        count.assign(buckets + 1, 0);
        for (std::size_t t = 0; t < kept; ++t) {
          bucket[t] = static_cast<std::uint32_t>(std::min<double>(static_cast<double>(buckets - 1), fd[t] * per_bucket));
          ++count[bucket[t] + 1];
        }
        for (std::size_t u = 1; u <= buckets; ++u) count[u] += count[u - 1];
        for (std::size_t t = 0; t < kept; ++t) {
          const std::uint32_t at = count[bucket[t]]++;
          sd[at] = fd[t];
          si[at] = fi[t];
        }
        // Only the buckets up to the k-th point's need the insertion sort.
        const double kth = sd[static_cast<std::size_t>(k) - 1];
        const std::size_t sorted_end = count[static_cast<std::uint32_t>(std::min<double>(static_cast<double>(buckets - 1), kth * per_bucket))];
        for (std::size_t t = 1; t < sorted_end; ++t) {
          const double dv = sd[t];
          const Index iv = si[t];
          std::size_t at = t;
          while (at > 0 && (sd[at - 1] > dv || (sd[at - 1] == dv && si[at - 1] > iv))) {
            sd[at] = sd[at - 1];
            si[at] = si[at - 1];
            --at;
          }
          sd[at] = dv;
          si[at] = iv;
        }
        std::copy(sd.begin(), sd.begin() + k, d2.begin());
        std::copy(si.begin(), si.begin() + k, idx.begin());
        last_reach = std::sqrt(d2[k - 1]);
        emit(self, idx.data(), d2.data(), k);
      }
    }
  }, stage, 16);
}

}  // namespace pointscale
