// Orientation of a level without given normals: each cluster's normal at its anchor, fitted to
// the anchors around it and oriented by spanning-tree propagation (outward on closed shapes).
// decompose_rayshoot orients level 0 this way, through orientation_reference; decompose orients
// its finest level with the projection's normals at the anchors and the level's own
// neighbourhoods (orient_cluster_normals, level_turns.h), which it has at hand.
#pragma once
#include "pointscale/detail/level_normals.h"

namespace pointscale {

// anchors  #C by 3, support_centroids of the level. Returns #C by 3 unit normals, each of
// either sign.
Points anchor_normals(const Points& anchors, const LevelSupport& support);

// The same, oriented. Returns #C by 3 oriented unit normals.
Points oriented_anchor_normals(const Points& anchors, const LevelSupport& support);

// normals  #C by 3 unit normals of the level's clusters (either sign), oriented in place like
// oriented_anchor_normals, over the first 12 of each cluster's neighbourhood (support), which
// the level found already. anchors: #C by 3, where the normals are.
void orient_cluster_normals(const Points& anchors, Points& normals, const LevelSupport& support);

// Per point, its cluster's oriented anchor normal: #P by 3 orientation references.
// level  #P by 3.
Points orientation_reference(const Points& level, const LevelSupport& support);

}  // namespace pointscale
