// Orientation of a level without given normals: each cluster's normal at its anchor, fitted to
// the anchors around it and oriented by spanning-tree propagation (outward on closed shapes).
// decompose orients its finest level this way (level_turns.h), and decompose_rayshoot level 0
// through orientation_reference.
#pragma once
#include "pointscale/detail/level_normals.h"

namespace pointscale {

// anchors  #C by 3, support_centroids of the level. Returns #C by 3 unit normals, each of
// either sign.
Points anchor_normals(const Points& anchors, const LevelSupport& support);

// The same, oriented. Returns #C by 3 oriented unit normals.
Points oriented_anchor_normals(const Points& anchors, const LevelSupport& support);

// Per point, its cluster's oriented anchor normal: #P by 3 orientation references.
// level  #P by 3.
Points orientation_reference(const Points& level, const LevelSupport& support);

}  // namespace pointscale
