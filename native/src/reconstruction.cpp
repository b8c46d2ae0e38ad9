#include "pointscale/reconstruction.h"

#include <utility>

#include "pointscale/parallel.h"

namespace pointscale {

namespace {

// p: P^0 to start from. Edited, level 0's normals are computed and oriented by the stored
// ones turned by reference_rotation (per level-0 cluster); unedited, they are the stored ones.
Reconstruction reconstruct_levels(const MultiscaleModel& model, const Eigen::MatrixXd& gains, Points p,
                                  bool edited, const std::vector<Mat3>* reference_rotation, bool keep_levels,
                                  int upto, const ProgressCallback* progress) {
  const int k = model.bands();
  if (upto < 0 || upto > k) upto = k;
  const bool per_point = gains.cols() > 1;
  const ProgressStage all{progress, 0.0, 1.0};
  Reconstruction out;
  if (keep_levels) out.levels.push_back(p);
  // Level l's normals orient level l + 1's. They are computed into whichever of two buffers
  // the level before does not hold, so each level reuses the storage of the one before it.
  // The unedited base's normals are the stored ones, bit for bit (decompose made them with
  // the same function and oriented them), so level 0 then reads them in place.
  Points buffers[2];
  const Points* previous = &model.base_normals;
  for (int l = 0; l < upto; ++l) {
    const LevelSupport& s = model.support[l];
    const ProgressStage stage = all.sub(double(l) / upto, double(l + 1) / upto);
    const Points* normals = previous;
    if (l > 0 || edited) {
      Points& into = previous == &buffers[0] ? buffers[1] : buffers[0];
      level_normals(p, s, *previous, stage, into, l == 0 ? reference_rotation : nullptr);
      normals = &into;
    }
    const Points& nrm = *normals;
    parallel_for(static_cast<std::size_t>(p.rows()), [&](std::size_t b, std::size_t e) {
      for (std::size_t ii = b; ii < e; ++ii) {
        const Eigen::Index i = static_cast<Eigen::Index>(ii);
        const double g = per_point ? gains(l, i) : gains(l, 0);
        p.row(i) += (g * model.details(l, i)) * nrm.row(i);
      }
    }, {}, 4096);
    if (keep_levels) { out.levels.push_back(p); out.normals.push_back(nrm); }
    previous = normals;
  }
  out.positions = std::move(p);
  return out;
}

}  // namespace

Reconstruction reconstruct(const MultiscaleModel& model, const Eigen::MatrixXd& gains, const Points* base,
                           bool keep_levels, int upto, const ProgressCallback* progress) {
  if (base) return reconstruct_from_base(model, gains, *base, keep_levels, upto, progress);
  return reconstruct_levels(model, gains, model.base, false, nullptr, keep_levels, upto, progress);
}

Reconstruction reconstruct_from_base(const MultiscaleModel& model, const Eigen::MatrixXd& gains, Points base,
                                     bool keep_levels, int upto, const ProgressCallback* progress) {
  const std::vector<Mat3> rotation = transported_rotations(model.base, base, model.support[0]);
  return reconstruct_levels(model, gains, std::move(base), true, &rotation, keep_levels, upto, progress);
}

}  // namespace pointscale
