// Local sample spacing: the kernel width is h = factor x spacing (Sec. 2 and 5.2).
#pragma once
#include "pointscale/spatial_index.h"

namespace pointscale {

// Mean distance of each point of `index` to its `k` nearest other points, ignoring exact
// duplicates. Points whose neighbours all coincide with them get the median spacing.
// Returns #P spacings.
Eigen::VectorXd local_spacing(const SpatialIndex& index, int k = 6);

// Its two steps, for callers that query the neighbours anyway (support_neighbours.h): one
// point's spacing from its neighbours' squared distances, closest first (0 if all are 0)...
double spacing_from_neighbours(const double* squared_distances, int found, int k);
// ...and the median of the others for the points left at 0.
void fill_missing_spacing(Eigen::VectorXd& spacing);

}  // namespace pointscale
