#include "pointscale/encoding.h"
#include "pointscale/validation.h"

#include <algorithm>
#include <utility>

#include "pointscale/cluster_decimation.h"
#include "pointscale/sample_spacing.h"
#include "pointscale/detail/align_offsets.h"
#include "pointscale/detail/base_normals.h"
#include "pointscale/detail/build_level_support.h"
#include "pointscale/detail/project_from_afar.h"
#include "pointscale/detail/level_normals.h"

namespace pointscale {

MultiscaleModel encode_onto(const Points& points, const Points& base, const Points* base_normals,
                            const EncodeOptions& options, const ProgressCallback* progress) {
  validate(options);
  check_points(points, "points", min_coarse_points);
  check_points(base, "base_points", min_coarse_points);
  check_surface(base, "base_points", true);
  check_near(points, bounding_box_centre(base), "points", "base_points");
  check_normals(base_normals, base, "base_normals", "base_points");
  const ProgressStage all{progress, 0.0, 1.0};
  const Eigen::Index n = points.rows();
  const double scale = (points.colwise().maxCoeff() - points.colwise().minCoeff()).norm();
  const SpatialIndex base_index(base);
  const Eigen::VectorXd h = options.kernel * local_spacing(base_index, 6);
  MlsResult projected = project_from_afar(points, base_index, h, options.mls, all.sub(0.0, 0.6));

  // The level's own support, about as fine as the base (and never finer than the model).
  const auto target = static_cast<std::size_t>(std::min<Eigen::Index>(base.rows(), std::max<Eigen::Index>(1, n / 2)));
  MultiscaleModel model;
  {
    Clustering clusters = cluster_decimate(projected.positions, target, options.max_variation);
    LevelSupportRecipe recipe;
    recipe.kernel = options.kernel;
    model.support.push_back(build_level_support(std::move(clusters.labels), static_cast<Index>(clusters.centroids.rows()),
                                                points, projected.positions, options.mls.neighbors, recipe));
  }
  const LevelSupport& support = model.support[0];
  Points level = std::move(projected.positions);

  // Orientation from the base: its given normals, else outward by propagation over the base.
  const Points reference = nearest_normals(level, base_index, base_normals ? *base_normals : oriented_normals(base_index));

  const Alignment aligned = align_offsets(points, level, support, reference, options.consistency_iterations,
                                         1e-12 * scale, all.sub(0.6, 0.95), &base_index, &h, options.mls.neighbors);
  const Points normals = level_normals(level, support, reference);
  model.details.resize(1, n);
  for (Eigen::Index i = 0; i < n; ++i) model.details(0, i) = (points.row(i) - level.row(i)).dot(normals.row(i));
  model.base_normals = normals;
  model.base = std::move(level);
  LevelReport report;
  report.support_points = static_cast<std::size_t>(support.clusters);
  report.kernel_width = h.size() ? h.mean() : 0.0;
  report.not_converged = projected.not_converged;
  report.degenerate = projected.degenerate;
  report.consistency_iterations = aligned.iterations;
  report.consistency_residual = aligned.residual;
  report.pinned = aligned.kept;
  model.reports.push_back(report);
  all.report(1.0);
  return model;
}

}  // namespace pointscale
