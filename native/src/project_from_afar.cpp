#include "pointscale/detail/project_from_afar.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <vector>

#include "pointscale/parallel.h"
#include "pointscale/detail/plane_fit.h"

namespace pointscale {

MlsResult project_from_afar(const Points& x, const SpatialIndex& base, const Eigen::VectorXd& h,
                            const MlsOptions& options, const ProgressStage& stage) {
  const Eigen::Index n = x.rows();
  const int k = std::min<int>(options.neighbors, base.size());
  const Points& s = base.points();
  const Eigen::VectorXd inv_h2 = h.array().square().inverse();
  const int cap = std::max(options.max_iterations, 200);
  MlsResult out;
  out.positions.resize(n, 3);
  out.normals.resize(n, 3);
  std::vector<unsigned char> failed(n, 0), degenerate(n, 0);
  parallel_for(static_cast<std::size_t>(n), [&](std::size_t b, std::size_t e) {
    std::vector<Index> idx(k);
    std::vector<double> d2(k), ih2(k), w(k);
    for (std::size_t ii = b; ii < e; ++ii) {
      const Eigen::Index i = static_cast<Eigen::Index>(ii);
      const Vec3 p = x.row(i).transpose();
      base.knn(p.data(), 1, idx.data(), d2.data());
      Vec3 foot = s.row(idx[0]).transpose(), normal = Vec3::Zero(), last_foot = foot, last_normal = Vec3::Zero();
      bool ok = false, converged = false;
      double last_step = std::numeric_limits<double>::infinity(), safety = 1.0;
      for (int it = 0; it < cap; ++it) {
        const int found = base.knn(foot.data(), k, idx.data(), d2.data());
        for (int j = 0; j < found; ++j) ih2[j] = inv_h2(idx[j]);
        gaussian_weights(d2.data(), ih2.data(), found, w.data());
        const PlaneFit fit = fit_weighted_plane(s, idx.data(), w.data(), found, foot);
        if (!fit.ok) break;
        normal = fit.normal;
        if (ok && normal.dot(last_normal) < 0.0) normal = -normal;
        // The plain step swings with slope -(distance x curvature); the curvature seen between
        // the last two feet turns it into a Newton step, 1 / (1 + distance x curvature).
        double damping = 1.0;
        const double moved = (foot - last_foot).norm();
        if (ok && moved > 0.0) damping = 1.0 / (1.0 + std::abs((p - foot).dot(normal)) * (normal - last_normal).norm() / moved);
        ok = true;
        const Vec3 next = p - (p - fit.mean).dot(normal) * normal;
        const double step = (next - foot).norm();
        if (step > last_step) safety = std::max(safety * 0.5, 1.0 / 1024.0);
        last_step = step;
        last_foot = foot;
        last_normal = normal;
        foot += std::min(damping, safety) * (next - foot);
        // Keep the foot on the fitted plane while it moves in damped steps.
        foot -= (foot - fit.mean).dot(normal) * normal;
        if (step <= options.tolerance * h(idx[0])) { converged = true; break; }
      }
      out.positions.row(i) = foot.transpose();
      out.normals.row(i) = normal.transpose();
      if (!ok) degenerate[ii] = 1;
      else if (!converged) failed[ii] = 1;
    }
  }, stage, 64);
  for (Eigen::Index i = 0; i < n; ++i) { out.not_converged += failed[i]; out.degenerate += degenerate[i]; }
  return out;
}

}  // namespace pointscale
