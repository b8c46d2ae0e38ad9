// Local sample spacing: the kernel width is h = factor x spacing (Sec. 2 and 5.2).
#pragma once
#include "pointscale/spatial_index.h"

namespace pointscale {

// Mean distance of each point of `index` to its `k` nearest other points, ignoring exact
// duplicates. Points whose neighbours all coincide with them get the median spacing.
// Returns #P spacings.
Eigen::VectorXd local_spacing(const SpatialIndex& index, int k = 6);

}  // namespace pointscale
