// The normals of one level, as a function of that level's points alone, so that reconstruction
// can recompute them after the user edits the level (Sec. 8.1). Each decimation cluster is
// represented by one anchor point of the level, its member with the least detail; the normal at
// a point is the weighted least-squares plane normal (Eq. 3) of the nearby anchors. The cluster
// labels, each cluster's neighbour clusters and kernel widths are cached at decomposition time,
// like a mesh's connectivity.
#pragma once
#include <vector>

#include "pointscale/types.h"

namespace pointscale {

struct LevelSupport {
  IndexList labels;          // #P cluster of each point
  IndexList anchors;         // #C the point that represents each cluster
  Index clusters = 0;        // #C
  int neighbors = 0;         // K
  IndexList neighborhoods;   // #C by K nearest clusters of each cluster, itself first
  Eigen::VectorXd h;         // #C kernel width of each cluster
  IndexList frames;          // #C by 2: the neighbour clusters that span each cluster's frame
  // #P by 3: each point's query position in its cluster's frame, laid out by
  // cluster_layout.h: row t belongs to point cluster_layout(labels).members[t].
  // local_by_point / local_from_points convert.
  Points local;
};

// support.local in point order (row i for point i), and back: for saving and loading.
Points local_by_point(const LevelSupport& support);
void local_from_points(const Points& by_point, LevelSupport& support);

// The functions that build a level's support and evaluate its normals are internal:
// detail/level_normals.h.

}  // namespace pointscale
