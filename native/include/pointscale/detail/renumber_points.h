// decompose works on the points renumbered in the layout of its first clusters (cluster_layout.h),
// so that its per-point passes read and write memory in order, whatever order the input comes in
// (a random one, or a scanner's lines); the finished model is renumbered back to the input's
// numbering.
#pragma once
#include "pointscale/decomposition.h"
#include "pointscale/spatial_order.h"

namespace pointscale {

// rows #P by 3; order #P. Row t of the result is rows.row(order[t]).
Points gather_rows(const Points& rows, const IndexList& order);

// Numbers the points in the order of groups.members (#P): points #P by 3 and labels #P follow,
// and groups then lists 0..#P-1. Returns original: point i was point original[i] before.
IndexList number_by_groups(Points& points, IndexList& labels, LabelGroups& groups);

// Renumbers a model whose point i is input point original[i] (#P) to the input's numbering: the
// per-point arrays and each level's labels and anchors. The frame coordinates (support.local)
// stay as they are: the caller lays them out by cluster_layout.h, which gives the same rows in
// any numbering of the points.
void renumber_model(MultiscaleModel& model, const IndexList& original);

}  // namespace pointscale
