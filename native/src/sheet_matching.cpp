#include "pointscale/detail/sheet_matching.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <vector>

#include "pointscale/parallel.h"
#include "pointscale/spatial_index.h"
#include "pointscale/detail/knn_weights.h"

namespace pointscale {

namespace {

// How many of a query's nearest neighbours the sheets are found among: the search compares
// every pair, and the nearest show the sheets. Farther ones join the sheet of the one among
// them nearest in offset.
constexpr int sheet_neighbors = 32;

// The sheets among a query's neighbours (idx, nearest first): two lie on one sheet when they are
// joined by a chain of pairs whose offsets differ by at most twice the distance of their feet
// (a slope under 63 degrees over the base). Labels the found neighbours 0..sheets-1 in the order
// of their sheets' mean offsets; returns the count. stack, mean, count, rank, order: scratch.
int label_sheets(const Points& feet, const Eigen::VectorXd& offsets, const Index* idx, int found, int* sheet,
                 std::vector<int>& stack, std::vector<double>& mean, std::vector<int>& count,
                 std::vector<int>& rank, std::vector<int>& order) {
  constexpr double slope = 2.0;
  const int searched = std::min(found, sheet_neighbors);
  std::fill(sheet, sheet + found, -1);
  int sheets = 0;
  for (int s = 0; s < searched; ++s) {
    if (sheet[s] >= 0) continue;
    sheet[s] = sheets;
    stack.assign(1, s);
    while (!stack.empty()) {
      const int u = stack.back();
      stack.pop_back();
      for (int t = 0; t < searched; ++t) {
        if (sheet[t] >= 0) continue;
        const double apart = (feet.row(idx[u]) - feet.row(idx[t])).norm();
        if (std::abs(offsets(idx[u]) - offsets(idx[t])) <= slope * apart) {
          sheet[t] = sheets;
          stack.push_back(t);
        }
      }
    }
    ++sheets;
  }
  if (sheets == 1) {
    std::fill(sheet, sheet + found, 0);
    return 1;
  }
  for (int t = searched; t < found; ++t) {
    double best = std::numeric_limits<double>::infinity();
    for (int s = 0; s < searched; ++s) {
      const double miss = std::abs(offsets(idx[t]) - offsets(idx[s]));
      if (miss < best) { best = miss; sheet[t] = sheet[s]; }
    }
  }
  mean.assign(static_cast<std::size_t>(sheets), 0.0);
  count.assign(static_cast<std::size_t>(sheets), 0);
  rank.resize(static_cast<std::size_t>(sheets));
  for (int j = 0; j < found; ++j) { mean[sheet[j]] += offsets(idx[j]); ++count[sheet[j]]; }
  for (int g = 0; g < sheets; ++g) mean[g] /= count[g];
  order.resize(static_cast<std::size_t>(sheets));
  for (int g = 0; g < sheets; ++g) order[g] = g;
  std::stable_sort(order.begin(), order.end(), [&](int x, int y) { return mean[x] < mean[y]; });
  for (int r = 0; r < sheets; ++r) rank[order[r]] = r;
  for (int j = 0; j < found; ++j) sheet[j] = rank[sheet[j]];
  return sheets;
}

}  // namespace

Eigen::VectorXd offsets_on_matching_sheets(const Points& from, const Eigen::VectorXd& values, const Points& to,
                                           const Eigen::VectorXd& to_values, int k, const ProgressStage& stage) {
  const SpatialIndex index(from), own(to);
  const int k_own = std::min<int>(k, own.size());  // A's own neighbourhood, however few B has
  k = std::min<int>(k, index.size());
  Eigen::VectorXd out(to.rows());
  parallel_for(static_cast<std::size_t>(to.rows()), [&](std::size_t b, std::size_t e) {
    std::vector<Index> idx(k), own_idx(k_own);
    std::vector<double> d2(k), ih2(k), w(k), own_d2(k_own), mean;
    std::vector<int> sheet(k), own_sheet(k_own), stack, count, rank, order;
    for (std::size_t ii = b; ii < e; ++ii) {
      const Eigen::Index i = static_cast<Eigen::Index>(ii);
      const int found = knn_gaussian_weights(index, to.row(i).data(), k, idx.data(), d2.data(), ih2.data(), w.data());
      const int sheets = label_sheets(from, values, idx.data(), found, sheet.data(), stack, mean, count, rank, order);
      int chosen = -1;  // every neighbour
      if (sheets > 1) {
        const int own_found = own.knn(to.row(i).data(), k_own, own_idx.data(), own_d2.data());
        const int own_sheets = label_sheets(to, to_values, own_idx.data(), own_found, own_sheet.data(), stack, mean, count, rank, order);
        if (own_sheets == sheets) {
          // The sample's own sheet: the one of the neighbour that is the sample itself.
          for (int j = 0; j < own_found; ++j)
            if (own_idx[j] == static_cast<Index>(i)) chosen = own_sheet[j];
          if (chosen < 0) chosen = own_sheet[0];
        } else if (own_sheets > 1) {
          double best = std::numeric_limits<double>::infinity();
          for (int j = 0; j < found; ++j) {
            const double miss = std::abs(values(idx[j]) - to_values(i));
            if (miss < best) { best = miss; chosen = sheet[j]; }
          }
        }
      }
      double sum = 0.0, wsum = 0.0;
      for (int j = 0; j < found; ++j) {
        if (chosen >= 0 && sheet[j] != chosen) continue;
        sum += w[j] * values(idx[j]);
        wsum += w[j];
      }
      out(i) = sum / wsum;
    }
  }, stage, 512);
  return out;
}

}  // namespace pointscale
