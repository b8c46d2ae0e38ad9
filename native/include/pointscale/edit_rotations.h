// How an edit of the base turns the surface at each point, at the edit's own scale, so that
// reconstruction turns every level's normals with it and the detail follows the edit upright
// (Sec. 8.1, Fig. 5). Level normals refitted from an edited level's anchors cannot do this: at
// level 0 their kernel is the widest of the model, and an edit narrower than it is averaged
// away. The turn at a point is measured on its ring instead: the point and its nearest base
// points, found once on the unedited base, as a mesh's one-ring is.
#pragma once
#include <vector>

#include "pointscale/types.h"

namespace pointscale {

// Points per ring: the point itself and its 12 nearest.
constexpr int base_ring_size = 13;

// The rings of a base: #P by ring_size_for(#P) point indices, each row its point first.
IndexList base_rings(const Points& base);
inline int ring_size_for(Eigen::Index points) { return points < base_ring_size ? static_cast<int>(points) : base_ring_size; }

// Where each point's detail stands on the base: the base point nearest to the point itself
// (its finest level), so that the detail turns with the base beneath it, not with the spot its
// own base position happens to fall on (under tall detail the base positions of one feature
// spread over more than the feature). A nearest base point whose normal faces away from the
// point's own (another side of a thin part) is not taken: the point stands on its own.
// base, base_normals, finest  #P by 3. Returns #P base point indices.
IndexList base_feet(const Points& base, const Points& base_normals, const Points& finest);

// What edit_rotations found.
struct EditRotationReport {
  std::size_t unchanged = 0;  // rings the edit left as they were, to rounding: the identity
  std::size_t planar = 0;     // the turn of the ring's plane, then the twist about its normal
  std::size_t curved = 0;     // rings with no clear plane: the best rotation of the ring (Kabsch)
  std::size_t on_a_line = 0;  // rings whose points lie on a line: the cluster's rotation
};

// original, edited   #P by 3, the stored base and the edited one
// rings              #P by ring_size, from base_rings(original)
// cluster_rotation   #C rotations of the level-0 clusters (transported_rotations), with
// labels             #P each point's level-0 cluster: they pick the side of an edited ring's
//                    plane (so a turn past 90 degrees keeps its sign) and stand in where a
//                    ring has no plane
// Returns #P rotations. A ring the edit did not change, to within 1e-12 of the base's
// diagonal, gives exactly the identity, so an unedited round trip stays exact.
std::vector<Mat3> edit_rotations(const Points& original, const Points& edited, const IndexList& rings,
                                 int ring_size, const std::vector<Mat3>& cluster_rotation, const IndexList& labels,
                                 EditRotationReport* report = nullptr);

}  // namespace pointscale
