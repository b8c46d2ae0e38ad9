#include "pointscale/mls_projection.h"

#include <algorithm>
#include <cmath>
#include <utility>
#include <limits>

#include "pointscale/normal_estimation.h"
#include "pointscale/parallel.h"
#include "pointscale/plane_fit.h"

namespace pointscale {

MlsResult mls_project(const Points& x, const SpatialIndex& support, const Eigen::VectorXd& h,
                      const MlsOptions& options, const ProgressStage& stage) {
  const Eigen::Index n = x.rows();
  const int k = std::min<int>(options.neighbors, support.size());
  const Points& s = support.points();
  const Eigen::VectorXd inv_h2 = h.array().square().inverse();
  // Anisotropic weights: |d|^2 + (1/sheet^2 - 1)(n.d)^2 in place of |d|^2.
  Points estimated;
  const Points* sheet_normals = options.support_normals;
  if (!sheet_normals && options.thin_sheets) {
    estimated = pca_normals(support, std::min<int>(16, support.size()));
    sheet_normals = &estimated;
  }
  const double sheet_extra = sheet_normals ? 1.0 / (options.sheet * options.sheet) - 1.0 : 0.0;
  MlsResult out;
  out.positions.resize(n, 3);
  out.normals.resize(n, 3);
  std::vector<unsigned char> failed(n, 0), degenerate(n, 0);

  // Each point queries kc > k candidates once; later iterations take the k nearest of them to
  // the moved foot, and query again only when the foot has moved so far that a closer point
  // could lie outside the candidates (d_k + 2 moved > d_kc): the same neighbours as a fresh query.
  const int kc = std::min<int>(k + 8, support.size());
  parallel_for(static_cast<std::size_t>(n), [&](std::size_t b, std::size_t e) {
    std::vector<Index> idx(k), cand(kc);
    std::vector<double> d2(k), ih2(k), w(k), cand_d2(kc);
    std::vector<std::pair<double, Index>> order(kc);
    for (std::size_t i = b; i < e; ++i) {
      const Vec3 p = x.row(static_cast<Eigen::Index>(i)).transpose();
      Vec3 foot = p;
      Vec3 normal = Vec3::Zero();
      bool converged = false, ok = false;
      double last_step = std::numeric_limits<double>::infinity(), damping = 1.0;
      Vec3 queried = foot;
      int candidates = 0;
      double reach = 0.0;  // d_kc - d_k at the last query: how far the foot may move, twice over
      for (int it = 0; it < options.max_iterations; ++it) {
        if (candidates == 0 || 2.0 * (foot - queried).norm() >= reach) {
          queried = foot;
          candidates = support.knn(foot.data(), kc, cand.data(), cand_d2.data());
          const int kth = std::min(k, candidates) - 1;
          reach = candidates > k ? std::sqrt(cand_d2[candidates - 1]) - std::sqrt(cand_d2[kth]) : 0.0;
          if (candidates <= k) reach = std::numeric_limits<double>::infinity();  // all there is
        }
        for (int j = 0; j < candidates; ++j) order[j] = {(s.row(cand[j]).transpose() - foot).squaredNorm(), cand[j]};
        const int found = std::min(k, candidates);
        std::partial_sort(order.begin(), order.begin() + found, order.begin() + candidates);
        for (int j = 0; j < found; ++j) { d2[j] = order[j].first; idx[j] = order[j].second; }
        for (int j = 0; j < found; ++j) ih2[j] = inv_h2(idx[j]);
        if (sheet_normals) {
          for (int j = 0; j < found; ++j) {
            // Measured from the point being projected, not the moving foot, so that the foot
            // cannot drift towards the other sheet and take the weights along.
            const double along = sheet_normals->row(idx[j]).dot(s.row(idx[j]) - p.transpose());
            d2[j] += sheet_extra * along * along;
          }
        }
        gaussian_weights(d2.data(), ih2.data(), found, w.data());
        const PlaneFit fit = fit_weighted_plane(s, idx.data(), w.data(), found, foot);
        if (!fit.ok) break;
        ok = true;
        normal = fit.normal;
        const Vec3 next = p - (p - fit.mean).dot(normal) * normal;
        const double step = (next - foot).norm();
        // Near sharp features the foot point can swing back and forth: damp a growing step.
        if (step > last_step) damping = std::max(damping * 0.5, 1.0 / 64.0);
        last_step = step;
        foot += damping * (next - foot);
        if (step <= options.tolerance * h(idx[0])) { converged = true; break; }
      }
      out.positions.row(static_cast<Eigen::Index>(i)) = foot.transpose();
      out.normals.row(static_cast<Eigen::Index>(i)) = normal.transpose();
      if (!ok) degenerate[i] = 1;
      else if (!converged) failed[i] = 1;
    }
  }, stage, 128);
  for (Eigen::Index i = 0; i < n; ++i) { out.not_converged += failed[i]; out.degenerate += degenerate[i]; }
  return out;
}

}  // namespace pointscale
