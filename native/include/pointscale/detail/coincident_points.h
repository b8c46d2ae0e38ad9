// Points that coincide in the input (a scan's repeated returns, a mesh vertex split along a UV
// seam or a hard edge) must stay one point at every level and every gain. The MLS projection
// does not give them one place by itself: each is fitted relative to the query that serves it,
// so two copies can round apart, and where the iteration stops at its cap they can end up far
// apart; the level's anchor then moves away from its copies (align_level.h). decompose finds
// the copies once and gives each level's projection one place for them.
#pragma once
#include <utility>
#include <vector>

#include "pointscale/spatial_order.h"

namespace pointscale {

// The points equal to an earlier point of their group, bit for bit, as (copy, first) pairs,
// in index order. Only points of one group are compared: a decimation puts coincident points in
// one cluster, since every split tells them apart by their coordinates alone.
// points  #P by 3
// groups  the points grouped (cluster_layout.h), each group's members in any order
// sides   #P by 3 or null: with thin sheets, copies must also face the same side (the two
//         faces of a sheet of no thickness are two surfaces)
std::vector<std::pair<Index, Index>> coincident_points(const Points& points, const LabelGroups& groups,
                                                       const Points* sides = nullptr);

// Gives each copy its first's rows of a and b (#P by 3 each): one place and one normal.
void unify_coincident(const std::vector<std::pair<Index, Index>>& copies, Points& a, Points& b);

// The same for a level made consistent (make_offsets_normal.h), and its details (#P): each group
// of copies takes the rows of its level's anchor where one of them is the anchor (the normals of
// the whole cluster were fitted to the anchor's place), else its first's. Their normals are one
// (coincident_points.h) up to the rounding of the batched fits, so the round trip stays exact to
// rounding for the copies too.
void unify_coincident(const std::vector<std::pair<Index, Index>>& copies, const IndexList& anchors, Points& level,
                      Points& normals, Eigen::MatrixXd::RowXpr details);

}  // namespace pointscale
