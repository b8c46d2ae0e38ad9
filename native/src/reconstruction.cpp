#include "pointscale/reconstruction.h"

#include "pointscale/parallel.h"

namespace pointscale {

Reconstruction reconstruct(const MultiscaleModel& model, const Eigen::MatrixXd& gains, const Points* base,
                           bool keep_levels, int upto, const ProgressCallback* progress) {
  const int k = model.bands();
  if (upto < 0 || upto > k) upto = k;
  const bool per_point = gains.cols() > 1;
  const ProgressStage all{progress, 0.0, 1.0};
  Reconstruction out;
  Points p = base ? *base : model.base;
  Points reference = base ? transported_references(model.base, *base, model.base_normals, model.support[0])
                          : model.base_normals;
  if (keep_levels) out.levels.push_back(p);
  for (int l = 0; l < upto; ++l) {
    const LevelSupport& s = model.support[l];
    Points normals = level_normals(p, s, reference, all.sub(double(l) / upto, double(l + 1) / upto));
    parallel_for(static_cast<std::size_t>(p.rows()), [&](std::size_t b, std::size_t e) {
      for (std::size_t ii = b; ii < e; ++ii) {
        const Eigen::Index i = static_cast<Eigen::Index>(ii);
        const double g = per_point ? gains(l, i) : gains(l, 0);
        p.row(i) += (g * model.details(l, i)) * normals.row(i);
      }
    }, {}, 4096);
    if (keep_levels) { out.levels.push_back(p); out.normals.push_back(normals); }
    reference = std::move(normals);
  }
  out.positions = std::move(p);
  return out;
}

}  // namespace pointscale
