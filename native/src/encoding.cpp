#include "pointscale/encoding.h"
#include "pointscale/validation.h"

#include <algorithm>
#include <utility>
#include <vector>

#include "pointscale/cluster_decimation.h"
#include "pointscale/parallel.h"
#include "pointscale/sample_spacing.h"
#include "pointscale/detail/align_level.h"
#include "pointscale/detail/base_normals.h"
#include "pointscale/detail/build_level_support.h"
#include "pointscale/detail/project_from_afar.h"
#include "pointscale/detail/level_normals.h"

namespace pointscale {

namespace {

struct Alignment {
  int iterations = 0;
  std::size_t kept = 0;    // points left where they were: no consistent position within reach
  double residual = 0.0;   // largest tangential part of fine - level left, in coordinates
};

// Makes fine - level lie along the level's recomputed normals: the level aligner (align_level.h)
// with encode's policy, which keeps a point whose consistent position is out of reach where it
// was and steps every slide back onto the base's MLS surface (base, h), so the level stays on
// it. reference #P by 3 orients the normals; normals receives the aligned level's (#P by 3),
// which the last step leaves as they are, since they depend on the anchors alone.
Alignment align_onto_base(const Points& fine, Points& level, const LevelSupport& support, const Points& reference,
                          int max_iterations, double stop, const ProgressStage& stage, const SpatialIndex& base,
                          const Eigen::VectorXd& h, int neighbors, Points& normals) {
  Points anchor_reference(support.clusters, 3);
  for (Index c = 0; c < support.clusters; ++c) anchor_reference.row(c) = reference.row(support.anchors[c]);
  LevelAligner aligner(fine, level, support, encode_alignment(base, h, neighbors));
  const AnchorAlignment anchors = aligner.align_anchors(anchor_reference, stop, max_iterations, stage);
  normals = level_normals(level, support, reference);
  Alignment out;
  out.iterations = anchors.iterations;
  out.kept = anchors.frozen + aligner.align_others(normals);
  std::vector<double> left(static_cast<std::size_t>(level.rows()), 0.0);
  parallel_for(left.size(), [&](std::size_t b, std::size_t e) {
    for (std::size_t ii = b; ii < e; ++ii) {
      const Eigen::Index i = static_cast<Eigen::Index>(ii);
      const Vec3 nrm = normals.row(i).transpose();
      const Vec3 d = (fine.row(i) - level.row(i)).transpose();
      left[ii] = (d - d.dot(nrm) * nrm).norm();
    }
  });
  out.residual = *std::max_element(left.begin(), left.end());
  stage.report(1.0);
  return out;
}

}  // namespace

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

  Points normals;
  const Alignment aligned = align_onto_base(points, level, support, reference, options.consistency_iterations,
                                            1e-12 * scale, all.sub(0.6, 0.95), base_index, h, options.mls.neighbors,
                                            normals);
  model.details.resize(1, n);
  for (Eigen::Index i = 0; i < n; ++i) model.details(0, i) = (points.row(i) - level.row(i)).dot(normals.row(i));
  model.base_normals = std::move(normals);
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
