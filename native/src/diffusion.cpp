#include "pointscale/diffusion.h"
#include "pointscale/validation.h"

#include <algorithm>

#include "pointscale/parallel.h"
#include "pointscale/spatial_index.h"

namespace pointscale {

double taubin_mu(double lambda, double pass_band) { return 1.0 / (pass_band - 1.0 / lambda); }

namespace {

// to = from + step * (mean of the neighbours - point).
void laplacian_step(const Points& from, Points& to, const IndexList& nb, int k, double step) {
  parallel_for(static_cast<std::size_t>(from.rows()), [&](std::size_t b, std::size_t e) {
    for (std::size_t i = b; i < e; ++i) {
      const Index* row = nb.data() + i * k;
      Vec3 mean = Vec3::Zero();
      int count = 0;
      for (int j = 0; j < k; ++j)
        if (row[j] != static_cast<Index>(i)) { mean += from.row(row[j]).transpose(); ++count; }
      const Eigen::Index r = static_cast<Eigen::Index>(i);
      if (count == 0) { to.row(r) = from.row(r); continue; }
      to.row(r) = from.row(r) + step * (mean.transpose() / count - from.row(r));
    }
  }, {}, 1024);
}

}  // namespace

Points diffuse(const Points& points, const IndexList& neighborhoods, int k, const DiffusionOptions& options,
               const ProgressStage& stage) {
  Points a = points, b(points.rows(), 3);
  for (int it = 0; it < options.iterations; ++it) {
    stage.report(static_cast<double>(it) / std::max(1, options.iterations));
    laplacian_step(a, b, neighborhoods, k, options.lambda);
    if (options.mu != 0.0) {
      laplacian_step(b, a, neighborhoods, k, options.mu);
    } else {
      a.swap(b);
    }
  }
  stage.report(1.0);
  return a;
}

Points diffuse(const Points& points, const DiffusionOptions& options, const ProgressStage& stage) {
  validate(options);
  check_points(points);
  check_extent(points, "points", false);
  const SpatialIndex index(points);
  const int k = std::min<int>(options.neighbors, index.size());
  const IndexList nb = knn_graph(index, k, stage.sub(0.0, 0.2));
  return diffuse(points, nb, k, options, stage.sub(0.2, 1.0));
}

}  // namespace pointscale
