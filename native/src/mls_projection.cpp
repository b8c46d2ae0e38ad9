#include "pointscale/mls_projection.h"

#include <algorithm>
#include <cmath>
#include <utility>
#include <limits>

#include "pointscale/candidate_plane.h"
#include "pointscale/normal_estimation.h"
#include "pointscale/parallel.h"
#include "pointscale/spatial_order.h"

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
  const bool given = options.order && options.order->size() == static_cast<std::size_t>(n);
  const IndexList own_order = given ? IndexList() : morton_order(x);
  const IndexList& order = given ? *options.order : own_order;
  parallel_for(static_cast<std::size_t>(n), [&](std::size_t b, std::size_t e) {
    std::vector<Index> cand(kc);
    std::vector<double> cand_d2(kc);
    CandidateSet set;
    for (std::size_t t = b; t < e; ++t) {
      const auto i = static_cast<std::size_t>(order[t]);
      const Vec3 p = x.row(static_cast<Eigen::Index>(i)).transpose();
      // The foot and the plane are kept relative to p, as the candidates are.
      Vec3 foot = Vec3::Zero();
      Vec3 normal = Vec3::Zero();
      bool converged = false, ok = false;
      double last_step = std::numeric_limits<double>::infinity(), damping = 1.0;
      Vec3 queried = foot;
      int candidates = 0;
      double reach = 0.0;  // d_kc - d_k at the last query: how far the foot may move, twice over
      for (int it = 0; it < options.max_iterations; ++it) {
        if (candidates == 0 || 2.0 * (foot - queried).norm() >= reach) {
          queried = foot;
          const Vec3 at = p + foot;
          candidates = support.knn(at.data(), kc, cand.data(), cand_d2.data());
          const int kth = std::min(k, candidates) - 1;
          reach = candidates > k ? std::sqrt(cand_d2[candidates - 1]) - std::sqrt(cand_d2[kth]) : 0.0;
          if (candidates <= k) reach = std::numeric_limits<double>::infinity();  // all there is
          set.resize(candidates);
          for (int j = 0; j < candidates; ++j) {
            const Index c = cand[j];
            set.x[j] = s(c, 0) - p.x(); set.y[j] = s(c, 1) - p.y(); set.z[j] = s(c, 2) - p.z();
            set.h[j] = h(c);
            set.inv_h2[j] = inv_h2(c);
            // Measured from the point being projected, not the moving foot, so that the foot
            // cannot drift towards the other sheet and take the weights along.
            double along = 0.0;
            if (sheet_normals) along = sheet_normals->row(c).dot(s.row(c) - p.transpose());
            set.extra[j] = sheet_extra * along * along;
          }
        }
        double nearest_h = 0.0;
        const PlaneFit fit = fit_nearest_plane(set, k, foot, nearest_h);
        if (!fit.ok) break;
        ok = true;
        normal = fit.normal;
        const Vec3 next = fit.mean.dot(normal) * normal;  // p projected onto the plane, relative to p
        const double step = (next - foot).norm();
        // Near sharp features the foot point can swing back and forth: damp a growing step.
        if (step > last_step) damping = std::max(damping * 0.5, 1.0 / 64.0);
        last_step = step;
        foot += damping * (next - foot);
        if (step <= options.tolerance * nearest_h) { converged = true; break; }
      }
      foot += p;
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
