// The one layout rule of a level's per-point rows. support.local (level_support.h) and every
// grouping that walks it list the points cluster by cluster, in cluster order, and within a
// cluster in the input's order. Clusters are numbered along the decimation's split tree, so the
// whole is a spatial order, and a cluster's members read consecutive rows. decompose numbers its
// points in this order from its first decimation on (renumber_points.h), and Reconstructor keeps
// level 0's; both still take each cluster's points in input order, so every fit sums in the
// order that the input's numbering gives, bit for bit. Everything else refers here.
#pragma once
#include "pointscale/spatial_order.h"

namespace pointscale {

// labels  #P cluster of each point, in [0, clusters)
// visit   #P the points' current numbers in the input's order (inverse_order of a
//         renumbering), or nullptr when the points are in the input's numbering
// Returns the points grouped by cluster in the layout above.
LabelGroups cluster_layout(const IndexList& labels, Index clusters, const Index* visit = nullptr);

}  // namespace pointscale
