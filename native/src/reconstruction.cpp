#include "pointscale/reconstruction.h"

#include <utility>

#include "pointscale/parallel.h"

namespace pointscale {

void reconstruct_levels_in_place(const MultiscaleModel& model, const Eigen::MatrixXd& gains, Points& p, bool edited,
                                 const std::vector<Mat3>* reference_rotation, Reconstruction* kept, int upto,
                                 const ProgressCallback* progress, ReconstructionWorkspace* workspace) {
  const int k = model.bands();
  if (upto < 0 || upto > k) upto = k;
  const bool per_point = gains.cols() > 1;
  const ProgressStage all{progress, 0.0, 1.0};
  if (kept) kept->levels.push_back(p);
  // Level l's normals orient level l + 1's. They are computed into whichever of two buffers
  // the level before does not hold, so each level reuses the storage of the one before it.
  // The unedited base's normals are the stored ones, bit for bit (decompose made them with
  // the same function and oriented them), so level 0 then reads them in place.
  ReconstructionWorkspace own;
  ReconstructionWorkspace& ws = workspace ? *workspace : own;
  const Points* previous = &model.base_normals;
  for (int l = 0; l < upto; ++l) {
    const LevelSupport& s = model.support[l];
    const ProgressStage stage = all.sub(double(l) / upto, double(l + 1) / upto);
    const Points* normals = previous;
    if (l > 0 || edited) {
      Points& into = previous == &ws.normals[0] ? ws.normals[1] : ws.normals[0];
      const LabelGroups* groups = static_cast<std::size_t>(l) < ws.groups.size() ? &ws.groups[l] : nullptr;
      level_normals(p, s, *previous, stage, into, l == 0 ? reference_rotation : nullptr, groups,
                    workspace ? &ws.centroids : nullptr);
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
    if (kept) { kept->levels.push_back(p); kept->normals.push_back(nrm); }
    previous = normals;
  }
}

namespace {

Reconstruction reconstruct_levels(const MultiscaleModel& model, const Eigen::MatrixXd& gains, Points p, bool edited,
                                  const std::vector<Mat3>* reference_rotation, bool keep_levels, int upto,
                                  const ProgressCallback* progress, ReconstructionWorkspace* workspace) {
  Reconstruction out;
  reconstruct_levels_in_place(model, gains, p, edited, reference_rotation, keep_levels ? &out : nullptr, upto,
                              progress, workspace);
  out.positions = std::move(p);
  return out;
}

}  // namespace

Reconstruction reconstruct(const MultiscaleModel& model, const Eigen::MatrixXd& gains, const Points* base,
                           bool keep_levels, int upto, const ProgressCallback* progress,
                           ReconstructionWorkspace* workspace) {
  if (base) return reconstruct_from_base(model, gains, *base, keep_levels, upto, progress, workspace);
  return reconstruct_levels(model, gains, model.base, false, nullptr, keep_levels, upto, progress, workspace);
}

Reconstruction reconstruct_from_base(const MultiscaleModel& model, const Eigen::MatrixXd& gains, Points base,
                                     bool keep_levels, int upto, const ProgressCallback* progress,
                                     ReconstructionWorkspace* workspace) {
  const std::vector<Mat3> rotation = transported_rotations(model.base, base, model.support[0]);
  return reconstruct_levels(model, gains, std::move(base), true, &rotation, keep_levels, upto, progress, workspace);
}

}  // namespace pointscale
