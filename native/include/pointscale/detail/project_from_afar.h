// Projection onto a base surface from afar, for encode_onto and morph (Sec. 8.2, 8.3).
#pragma once
#include "pointscale/mls_projection.h"

namespace pointscale {

// Closest points on the MLS surface of `base` for points that may lie far from it (many kernel
// widths, beyond the surface's radius of curvature). mls_project's fixed-point iteration swings
// with slope -distance x curvature there, so this starts at the nearest sample, where the first
// fit is well posed, scales each step by 1 / (1 + distance x curvature) with the curvature seen
// between the last two feet (a Newton step), and halves it further whenever a step grows.
// x  #X by 3; base  index on the #B samples; h  #B kernel widths.
MlsResult project_from_afar(const Points& x, const SpatialIndex& base, const Eigen::VectorXd& h,
                            const MlsOptions& options, const ProgressStage& stage = {});

}  // namespace pointscale
