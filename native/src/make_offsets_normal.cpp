#include "pointscale/detail/make_offsets_normal.h"

#include "pointscale/parallel.h"
#include "pointscale/detail/align_level.h"
#include "pointscale/detail/release_memory.h"
#include "pointscale/detail/level_normals.h"

namespace pointscale {

Consistency make_offsets_normal(const Points& fine, Points& level, const LevelSupport& support,
                                const LabelGroups& layout, const Points& anchor_reference, double scale,
                                int max_iterations, const ProgressStage& stage, Eigen::MatrixXd::RowXpr details,
                                Points& normals) {
  LevelAligner aligner(fine, level, support, decompose_alignment());
  const AnchorAlignment anchors = aligner.align_anchors(anchor_reference, 1e-12 * scale, max_iterations, stage);
  // The iteration's temporaries go back to the system before the peak. This is the only trim
  // within a step: trims at its start and after the decimation lowered no peak, and the next
  // step's arrays faulted the same pages in again.
  release_free_memory();
  // Unoriented normals (the eigenvector's own sign): the detail along them does not depend on
  // the sign, and decompose orients both once level 0 is known.
  level_normals(level, support, Points(), {}, normals, &layout);
  aligner.align_others(normals);
  parallel_for(static_cast<std::size_t>(level.rows()), [&](std::size_t b, std::size_t e) {
    for (std::size_t ii = b; ii < e; ++ii) {
      const Eigen::Index i = static_cast<Eigen::Index>(ii);
      details(i) = (fine.row(i) - level.row(i)).dot(normals.row(i));
    }
  });
  stage.report(1.0);
  Consistency out;
  out.iterations = anchors.iterations;
  out.residual = anchors.residual;
  out.pinned = anchors.frozen;
  return out;
}

}  // namespace pointscale
