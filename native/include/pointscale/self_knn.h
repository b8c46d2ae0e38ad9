// Every point's k nearest neighbours among the points themselves, all at once: the rows of a
// kNN graph or of a level's support, asked for every point of an index. A uniform grid serves
// them: the points of a cell share one gathered candidate set (the 27 cells around it), and a
// row is exact when its k-th distance is below the distance to that block's border; a query
// for which it is not goes to the kd-tree. Same answers as SpatialIndex::knn, except that
// points at exactly the same distance come in index order in the rows the grid answers (the
// rows the tree answers, and every row of a set under 4096 points, keep nanoflann's visit
// order). The squared distances are summed as nanoflann sums them, and both files are built
// without contracting multiply-adds, so that the two kinds of rows agree to the bit.
#pragma once
#include <functional>

#include "pointscale/progress.h"
#include "pointscale/spatial_index.h"
#include "pointscale/types.h"

namespace pointscale {

// emit(i, indices, squared_distances, found): point i's min(k, #P) nearest points of the
// index (itself among them), closest first. Called once per point, from worker threads; the
// arrays are valid only during the call.
using SelfKnnSink = std::function<void(Index, const Index*, const double*, int)>;

// index  the #P points, which are also the queries
// k      neighbours per point
void self_knn(const SpatialIndex& index, int k, const SelfKnnSink& emit, const ProgressStage& stage = {});

}  // namespace pointscale
