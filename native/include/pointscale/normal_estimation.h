// Point normals from local plane fits, and their consistent orientation.
#pragma once
#include "pointscale/progress.h"
#include "pointscale/spatial_index.h"

namespace pointscale {

// Unit PCA normals of the k-neighbourhood of every point (sign arbitrary). Points whose
// neighbourhood has no plane get a zero row. Returns #P by 3.
Points pca_normals(const SpatialIndex& index, int k, const ProgressStage& stage = {});

// Flips rows of `normals` (#P by 3) so that they agree along a minimum spanning tree of the
// k-nearest-neighbour graph weighted by 1 - |n_i . n_j| (Hoppe et al. 1992). Every connected
// piece starts at its point farthest from the cloud's centroid, oriented away from it, so closed
// shapes end up with outward normals.
void orient_normals(const SpatialIndex& index, Points& normals, int k);

}  // namespace pointscale
