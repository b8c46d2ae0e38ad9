// A level's normals from its points alone (level_support.h), and the steps that build the
// support they are read from.
#pragma once
#include <vector>

#include "pointscale/level_support.h"
#include "pointscale/progress.h"
#include "pointscale/spatial_order.h"

namespace pointscale {

// Chooses each cluster's frame and stores every point's coordinates in it. The normal of a
// point is evaluated at that query position, which moves with the centroids only, so a point's
// normal does not depend on the point itself: this keeps the offsets-along-normals condition
// solvable even where detail is larger than the level's radius of curvature.
// centroids #C by 3 from support_centroids(positions); positions #P by 3. groups: the points
// grouped by support.labels in the layout of cluster_layout.h, if the caller has them already.
void attach_frames(const Points& centroids, const Points& positions, LevelSupport& support,
                   const LabelGroups* groups = nullptr);

// Normals of a level from its points alone: centroids, then frames, then support_normals.
Points level_normals(const Points& level, const LevelSupport& support, const Points& reference,
                     const ProgressStage& stage = {});

// The same into `normals` (#P by 3), reusing its storage when it has the size already. For
// calls over and over (Reconstructor), groups: the points grouped by support.labels in the
// layout of cluster_layout.h (or the same groups with the members renumbered alike), and
// centroids: storage for the anchors' rows.
void level_normals(const Points& level, const LevelSupport& support, const Points& reference,
                   const ProgressStage& stage, Points& normals, const LabelGroups* groups = nullptr,
                   Points* centroids = nullptr);

// level_normals at the members of some clusters only, from the anchors' positions alone
// (centroids #C by 3, support_centroids of the level: the normals need nothing else, so a
// finished level can be dropped and its anchors kept): #W by 3, the rows of the points of
// those clusters, cluster by cluster (which[j]: the point of row j). Each cluster's members
// are fitted together as in level_normals, so the rows are bitwise the same as there.
// clusters: flags, #C (nonzero: evaluate that cluster's members).
// rank: #P, when support.local lists each cluster's points by rank rather than by index.
Points anchor_normals_of_clusters(const Points& centroids, const LevelSupport& support,
                                  const std::vector<unsigned char>& clusters, IndexList& which,
                                  const IndexList* rank = nullptr);

// The anchors' positions in the level. level  #P by 3; returns #C by 3 (or writes them into
// out, reusing its storage).
Points support_centroids(const Points& level, const LevelSupport& support);
void support_centroids(const Points& level, const LevelSupport& support, Points& out);

// Picks each cluster's anchor: the member with the smallest |fine - level|, whose own normal then
// barely depends on itself, so the offsets-along-normals condition converges quickly. Among equals
// the first in index order, or the one of lowest rank (#P) when given.
void choose_anchors(const Points& fine, const Points& level, LevelSupport& support, const Index* rank = nullptr);

// Unit normals at the query points, each fitted to the centroids around its cluster, with the
// sign chosen so that n . reference >= 0 (a zero reference row keeps the eigenvector's sign).
// query       #Q by 3 positions
// query_labels #Q cluster of each query point
// centroids   #C by 3, from support_centroids
// reference   #Q by 3 orientation references, or empty (0 rows) to keep every eigenvector's sign
Points support_normals(const Points& query, const Index* query_labels, const Points& centroids,
                       const LevelSupport& support, const Points& reference,
                       const ProgressStage& stage = {});

// support_normals with one query per listed cluster: query t is in cluster clusters[t] (#Q,
// each cluster at most once). The work is in proportion to #Q, not #C: the consistency
// iteration of a decomposition asks for fewer and fewer of a level's anchors.
Points support_normals_of(const Points& query, const IndexList& clusters, const Points& centroids,
                          const LevelSupport& support, const Points& reference, const ProgressStage& stage = {});

}  // namespace pointscale
