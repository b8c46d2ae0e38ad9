#include "pointscale/ray_shooting.h"

#include <stdexcept>

#include "pointscale/validation.h"

#include <cmath>
#include <limits>

#include "pointscale/cluster_decimation.h"
#include "pointscale/parallel.h"
#include "pointscale/detail/plane_fit.h"
#include "pointscale/sample_spacing.h"
#include "pointscale/detail/build_level_support.h"
#include "pointscale/detail/level_orientation.h"
#include "pointscale/detail/level_normals.h"

namespace pointscale {

RayHits shoot_rays(const Points& origins, const Points& directions, const SpatialIndex& support,
                   const Eigen::VectorXd& h, const RayOptions& options, const ProgressStage& stage) {
  validate(options);
  check_rays(origins, directions);
  if (h.size() != support.size()) throw std::invalid_argument("h must hold one kernel width per support point");
  check_near(origins, bounding_box_centre(support.points()), "origins", "onto");
  const Eigen::Index n = origins.rows();
  const int k = std::min<int>(options.neighbors, support.size());
  const Points& s = support.points();
  const Eigen::VectorXd inv_h2 = h.array().square().inverse();
  const double limit = options.max_distance;
  RayHits out;
  out.positions = origins;
  out.distances = Eigen::VectorXd::Zero(n);
  out.missed.assign(static_cast<std::size_t>(n), 0);

  parallel_for(static_cast<std::size_t>(n), [&](std::size_t b, std::size_t e) {
    std::vector<Index> idx(k);
    std::vector<double> d2(k), ih2(k), w(k);
    for (std::size_t ii = b; ii < e; ++ii) {
      const Eigen::Index i = static_cast<Eigen::Index>(ii);
      const Vec3 o = origins.row(i).transpose();
      const Vec3 d = directions.row(i).transpose();
      double t = 0.0, last_step = std::numeric_limits<double>::infinity(), damping = 1.0;
      bool hit = false;
      for (int it = 0; it < options.max_iterations; ++it) {
        const Vec3 x = o + t * d;
        const int found = support.knn(x.data(), k, idx.data(), d2.data());
        for (int j = 0; j < found; ++j) ih2[j] = inv_h2(idx[j]);
        floored_gaussian_weights(d2.data(), ih2.data(), found, w.data());
        const PlaneFit fit = fit_weighted_plane(s, idx.data(), w.data(), found, x);
        if (!fit.ok) break;
        const double cosine = fit.normal.dot(d);
        if (std::abs(cosine) < options.min_cosine) break;  // the ray runs along the surface here
        const double next = t + (fit.mean - x).dot(fit.normal) / cosine;
        const double step = std::abs(next - t);
        // The plane can tilt back and forth between iterations: damp a growing step.
        if (step > last_step) damping = std::max(damping * 0.5, 1.0 / 64.0);
        last_step = step;
        t += damping * (next - t);
        if (!(std::abs(t) <= limit)) break;
        if (step <= options.tolerance * h(idx[0])) { hit = true; break; }
      }
      // Where the iteration found no crossing, bracketing: the signed distance to the local
      // plane, normal turned along the ray, changes sign where the ray crosses the surface.
      // Searched outward from the origin in half-kernel steps, both ways in turn, and bisected:
      // a crossing where the distance vanishes (clean), or one where it does not (unclear: a fit
      // that jumps, or a fold of the fitted normal), which the search passes by. But past an
      // unclear one, a clean crossing more than 2 kernel widths off is another sheet (the far
      // side of a small closed part, through its inside), and the ray is a miss.
      if (!hit) {
        support.knn(o.data(), 1, idx.data(), d2.data());
        const double h0 = h(idx[0]);
        enum class Crossing { none, clean, unclear };
        auto nearest_crossing = [&](double range, double& found_t) {
          bool unclear = false;
          const double dt = 0.5 * h0;
          auto signed_distance = [&](double tt, bool& ok) {
            const Vec3 x = o + tt * d;
            const int found = support.knn(x.data(), k, idx.data(), d2.data());
            for (int j = 0; j < found; ++j) ih2[j] = inv_h2(idx[j]);
            floored_gaussian_weights(d2.data(), ih2.data(), found, w.data());
            const PlaneFit fit = fit_weighted_plane(s, idx.data(), w.data(), found, x);
            ok = fit.ok && std::abs(fit.normal.dot(d)) >= options.min_cosine;
            return ok ? (x - fit.mean).dot(fit.normal.dot(d) > 0 ? fit.normal : Vec3(-fit.normal)) : 0.0;
          };
          bool ok0;
          const double f0 = signed_distance(0.0, ok0);
          double side_t[2] = {0.0, 0.0}, side_f[2] = {f0, f0};
          bool side_ok[2] = {ok0, ok0};
          for (double step = dt; dt > 0.0 && step <= range; step += dt) {  // dt = 0 would never end
            for (int side = 0; side < 2; ++side) {
              const double tt = side ? -step : step;
              bool ok;
              const double f = signed_distance(tt, ok);
              if (ok && side_ok[side] && (f > 0) != (side_f[side] > 0)) {
                double lo = side_t[side], hi = tt, flo = side_f[side];
                for (int bisect = 0; bisect < 60; ++bisect) {
                  const double mid = 0.5 * (lo + hi);
                  bool okm;
                  const double fm = signed_distance(mid, okm);
                  if (!okm) break;
                  if ((fm > 0) == (flo > 0)) { lo = mid; flo = fm; } else { hi = mid; }
                }
                bool okt;
                const double ft = signed_distance(0.5 * (lo + hi), okt);
                found_t = 0.5 * (lo + hi);
                if (okt && std::abs(ft) <= 1e-3 * h0)
                  return unclear && std::abs(found_t) > 2.0 * h0 ? Crossing::unclear : Crossing::clean;
                unclear = true;
              }
              side_t[side] = tt;
              side_f[side] = f;
              side_ok[side] = ok;
            }
          }
          return unclear ? Crossing::unclear : Crossing::none;
        };
        double nearer = 0.0;
        hit = nearest_crossing(std::min(limit, 16.0 * h0), nearer) == Crossing::clean;
        if (hit) t = nearer;
      }
      if (hit) {
        // The MLS zero set runs on past the samples (over holes and boundaries): a hit farther
        // than 3 kernel widths from every sample is no hit.
        const Vec3 x = o + t * d;
        support.knn(x.data(), 1, idx.data(), d2.data());
        if (d2[0] > 9.0 * h(idx[0]) * h(idx[0])) hit = false;
      }
      if (hit) {
        out.positions.row(i) = (o + t * d).transpose();
        out.distances(i) = t;
      } else {
        out.missed[ii] = 1;
      }
    }
  }, stage, 128);
  for (unsigned char m : out.missed) out.miss_count += m;
  return out;
}

Points smoothed_support(const Points& fine, std::size_t target, double max_variation,
                        const DiffusionOptions* diffusion) {
  Clustering clusters = cluster_decimate(fine, target, max_variation);
  if (!diffusion) return std::move(clusters.centroids);
  return diffuse(clusters.centroids, *diffusion);
}

MultiscaleModel decompose_rayshoot(const Points& points, const Points* input_normals, const DecomposeOptions& options,
                                   const DiffusionOptions* diffusion, const RayOptions& rays, double fine_kernel,
                                   RayshootReport& report, const ProgressCallback* progress) {
  if (diffusion) validate(*diffusion, "diffusion_");
  check_decompose_input(points, input_normals, options, "decompose_rayshoot");
  validate(rays);
  check_kernel(fine_kernel, "fine_kernel");
  const Eigen::Index n = points.rows();
  const int k = options.levels - 1;
  const ProgressStage all{progress, 0.0, 1.0};
  std::vector<Points> smooth(k + 1), surface(k + 1);
  std::vector<Eigen::VectorXd> kernel(k + 1);
  smooth[k] = points;
  surface[k] = points;
  kernel[k] = fine_kernel * local_spacing(SpatialIndex(points), 6);

  // Top-down: the scale space and the surfaces S^l.
  for (int step = 0; step < k; ++step) {
    const int l = k - step;
    const ProgressStage stage = all.sub(0.5 * step / k, 0.5 * (step + 1) / k);
    const auto target = static_cast<std::size_t>(std::floor(std::pow(options.decimation, step + 1) * n));
    surface[l - 1] = smoothed_support(smooth[l], target, options.max_variation, diffusion);
    const SpatialIndex index(surface[l - 1]);
    kernel[l - 1] = options.kernel * local_spacing(index, 6);
    smooth[l - 1] = mls_project(smooth[l], index, kernel[l - 1], options.mls, stage.sub(0.1, 1.0)).positions;
  }

  // Bottom-up: shoot from each level along its normals onto the next finer surface.
  MultiscaleModel model;
  model.support.resize(k);
  model.reports.resize(k);
  model.details.resize(k, n);
  report.missed.assign(k, 0);
  report.missed_points.assign(k, {});
  Points level = std::move(smooth[0]);
  Points reference;
  for (int l = 0; l < k; ++l) {
    const ProgressStage stage = all.sub(0.5 + 0.5 * l / k, 0.5 + 0.5 * (l + 1) / k);
    // Anchors: the member nearest its cluster's centroid.
    const auto target = static_cast<std::size_t>(surface[l].rows());
    Clustering clusters = cluster_decimate(level, target, options.max_variation);
    Points centre(n, 3);
    for (Eigen::Index i = 0; i < n; ++i) centre.row(i) = clusters.centroids.row(clusters.labels[i]);
    LevelSupportRecipe recipe;
    recipe.kernel = options.kernel;
    LevelSupport& support = model.support[l];
    support = build_level_support(std::move(clusters.labels), static_cast<Index>(clusters.centroids.rows()), centre,
                                  level, options.mls.neighbors, recipe);

    if (l == 0) reference = input_normals ? *input_normals : orientation_reference(level, support);
    Points normals = level_normals(level, support, reference);
    const SpatialIndex target_index(surface[l + 1]);
    RayHits hits = shoot_rays(level, normals, target_index, kernel[l + 1], rays, stage.sub(0.2, 0.9));
    if (hits.miss_count > 0) {
      // Fall back to the orthogonal projection, measured along the normal.
      IndexList missed;
      for (Eigen::Index i = 0; i < n; ++i) if (hits.missed[i]) missed.push_back(static_cast<Index>(i));
      Points origins(static_cast<Eigen::Index>(missed.size()), 3);
      for (std::size_t m = 0; m < missed.size(); ++m) origins.row(m) = level.row(missed[m]);
      const MlsResult fallback = mls_project(origins, target_index, kernel[l + 1], options.mls);
      for (std::size_t m = 0; m < missed.size(); ++m) {
        const Index i = missed[m];
        hits.distances(i) = (fallback.positions.row(m) - level.row(i)).dot(normals.row(i));
      }
      report.missed[l] = hits.miss_count;
      report.missed_points[l] = std::move(missed);
    }
    for (Eigen::Index i = 0; i < n; ++i) model.details(l, i) = hits.distances(i);
    if (l == 0) { model.base = level; model.base_normals = normals; }
    LevelReport& r = model.reports[l];
    r.support_points = static_cast<std::size_t>(support.clusters);
    r.kernel_width = kernel[l].size() ? kernel[l].mean() : 0.0;
    r.not_converged = hits.miss_count;
    // The next level: exactly the displaced points, as reconstruction will rebuild them.
    for (Eigen::Index i = 0; i < n; ++i) level.row(i) += model.details(l, i) * normals.row(i);
    reference = std::move(normals);
  }
  all.report(1.0);
  return model;
}

}  // namespace pointscale
