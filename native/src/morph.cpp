#include "pointscale/morph.h"
#include "pointscale/validation.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <vector>
#include <stdexcept>

#include "pointscale/parallel.h"
#include "pointscale/detail/plane_fit.h"
#include "pointscale/sample_spacing.h"
#include "pointscale/detail/base_normals.h"
#include "pointscale/detail/project_from_afar.h"

namespace pointscale {

Eigen::VectorXd knn_interpolate(const Points& from, const Eigen::VectorXd& values, const Points& to, int k) {
  check_points(from, "from");
  check_points(to, "to");
  if (values.size() != from.rows()) throw std::invalid_argument("values must hold one value per point of from");
  check_neighbors(k, 1, "k");
  const SpatialIndex index(from);
  k = std::min<int>(k, index.size());
  Eigen::VectorXd out(to.rows());
  parallel_for(static_cast<std::size_t>(to.rows()), [&](std::size_t b, std::size_t e) {
    std::vector<Index> idx(k);
    std::vector<double> d2(k), ih2(k), w(k);
    for (std::size_t ii = b; ii < e; ++ii) {
      const Eigen::Index i = static_cast<Eigen::Index>(ii);
      const int found = index.knn(to.row(i).data(), k, idx.data(), d2.data());
      // Kernel from the farthest neighbour: the nearest ones dominate, a coincident one wins.
      const double h2 = std::max(d2[found - 1], 1e-300);
      std::fill(ih2.begin(), ih2.begin() + found, 1.0 / h2);
      gaussian_weights(d2.data(), ih2.data(), found, w.data());
      double sum = 0.0, wsum = 0.0;
      for (int j = 0; j < found; ++j) { sum += w[j] * values(idx[j]); wsum += w[j]; }
      out(i) = sum / wsum;
    }
  }, {}, 512);
  return out;
}

namespace {

// Projects x onto the base; returns the foot points, oriented normals and signed offsets.
struct Projection {
  Points foot, normals;
  Eigen::VectorXd detail;
};

Projection project_onto_base(const Points& x, const SpatialIndex& base, const Eigen::VectorXd& h,
                             const Points& base_normals, const MlsOptions& mls, const ProgressStage& stage,
                             MorphModel& report) {
  MlsResult r = project_from_afar(x, base, h, mls, stage);
  report.not_converged += r.not_converged;
  report.degenerate += r.degenerate;
  Projection p;
  const Points ref = nearest_normals(r.positions, base, base_normals);
  p.normals = std::move(r.normals);
  p.detail.resize(x.rows());
  for (Eigen::Index i = 0; i < x.rows(); ++i) {
    // A degenerate projection has no normal: fall back to the nearest base sample's.
    if (!(p.normals.row(i).squaredNorm() > 0.5)) p.normals.row(i) = ref.row(i);
    if (p.normals.row(i).dot(ref.row(i)) < 0.0) p.normals.row(i) *= -1.0;
    p.detail(i) = (x.row(i) - r.positions.row(i)).dot(p.normals.row(i));
    // Slide the foot within its tangent plane onto x's normal line (a tolerance-sized move),
    // so foot + detail * normal gives x back exactly.
    r.positions.row(i) = x.row(i) - p.detail(i) * p.normals.row(i);
  }
  p.foot = std::move(r.positions);
  return p;
}

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

// B's offsets on A's samples. Where B folds over the base (a bunny's ears over an ellipsoid),
// the nearest feet of B around an A foot come from two or more sheets of B, and a mean over
// them lands between the sheets. Where A folds there as well, into as many sheets, each A
// sample takes B's sheet of the same rank along the normal (inner to inner, outer to outer);
// into another number of sheets, the sheet of the B neighbour whose offset is nearest its own. Where A does not fold
// (or B does not), the mean over every neighbour, as knn_interpolate, bit for bit: a face's
// nose that folds in B only stays whole.
Eigen::VectorXd offsets_on_matching_sheets(const Points& from, const Eigen::VectorXd& values, const Points& to,
                                           const Eigen::VectorXd& to_values, int k, const ProgressStage& stage) {
  const SpatialIndex index(from), own(to);
  k = std::min<int>(k, index.size());
  const int k_own = std::min<int>(k, own.size());
  Eigen::VectorXd out(to.rows());
  parallel_for(static_cast<std::size_t>(to.rows()), [&](std::size_t b, std::size_t e) {
    std::vector<Index> idx(k), own_idx(k_own);
    std::vector<double> d2(k), ih2(k), w(k), own_d2(k_own), mean;
    std::vector<int> sheet(k), own_sheet(k_own), stack, count, rank, order;
    for (std::size_t ii = b; ii < e; ++ii) {
      const Eigen::Index i = static_cast<Eigen::Index>(ii);
      const int found = index.knn(to.row(i).data(), k, idx.data(), d2.data());
      const double h2 = std::max(d2[found - 1], 1e-300);
      std::fill(ih2.begin(), ih2.begin() + found, 1.0 / h2);
      gaussian_weights(d2.data(), ih2.data(), found, w.data());
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

}  // namespace

MorphModel morph(const Points& a, const Points& b, const Points& base, const Points* base_normals,
                 const MorphOptions& options, const ProgressCallback* progress) {
  validate(options);
  check_points(a, "points_a");
  check_points(b, "points_b");
  check_points(base, "base_points", min_coarse_points);
  check_surface(base, "base_points", true);
  const Vec3 centre = bounding_box_centre(base);
  check_near(a, centre, "points_a", "base_points");
  check_near(b, centre, "points_b", "base_points");
  check_normals(base_normals, base, "base_normals", "base_points");
  const ProgressStage all{progress, 0.0, 1.0};
  const SpatialIndex base_index(base);
  const Eigen::VectorXd h = options.kernel * local_spacing(base_index, 6);
  const Points oriented = base_normals ? *base_normals : oriented_normals(base_index);
  MorphModel out;
  Projection pa = project_onto_base(a, base_index, h, oriented, options.mls, all.sub(0.0, 0.45), out);
  Projection pb = project_onto_base(b, base_index, h, oriented, options.mls, all.sub(0.45, 0.9), out);
  out.detail_b = offsets_on_matching_sheets(pb.foot, pb.detail, pa.foot, pa.detail, options.interpolation_neighbors,
                                            all.sub(0.9, 1.0));
  out.base = std::move(pa.foot);
  out.normals = std::move(pa.normals);
  out.detail_a = std::move(pa.detail);
  all.report(1.0);
  return out;
}

}  // namespace pointscale
