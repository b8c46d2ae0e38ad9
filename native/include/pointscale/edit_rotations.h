// How an edit of the base turns the surface at each point, at the edit's own scale, so that
// reconstruction turns every level's normals with it and the detail follows the edit upright
// (Sec. 8.1, Fig. 5). Level normals refitted from an edited level's anchors cannot do this: at
// level 0 their kernel is the widest of the model, and an edit narrower than it is averaged
// away. The turn at a point is measured on its ring instead: the point and its nearest base
// points, found once on the unedited base, as a mesh's one-ring is.
#pragma once
#include <array>
#include <vector>

#include "pointscale/types.h"

namespace pointscale {

// Points per ring of the fold tests (folds.h): the point itself and its 12 nearest.
constexpr int base_ring_size = 13;
// Points per ring that measures an edit's turn: the point itself and its 24 nearest. A turn
// measured over 12 neighbours follows the sampling's noise on a scan; a fold is a matter of the
// nearest neighbours only.
constexpr int edit_ring_size = 25;

// The rings of a base: #P by ring_size_for(#P, size) point indices, each row its point first.
// parts: #P part labels (connected_parts.h), or empty: a ring then holds points of its own part
// only, and a part of fewer points than a ring fills the rest of its rings with the point itself.
inline int ring_size_for(Eigen::Index points, int size = base_ring_size) {
  return points < size ? static_cast<int>(points) : size;
}
IndexList base_rings(const Points& base, const IndexList& parts = {}, int size = base_ring_size);

// The rings that measure an edit's turn: base_rings of edit_ring_size, but with one point per
// position. Points that coincide (a scan's repeated returns, a vertex welded twice) measure no
// turn, and a ring filled by them lay on a line or at a point: 24 copies of one point took a
// neighbour's whole ring, and a rigid turn of the base then turned its detail wrongly (8% of
// the model). A ring with fewer places than it has room for fills the rest with the point itself.
IndexList edit_rings(const Points& base, const IndexList& parts = {});

// Where each point's detail stands on the base: the base point nearest to the line through
// the point itself (its finest level) along its base normal, that is right below it, found by
// walking the rings downhill, so that the detail turns with the base beneath it, not with the
// spot its own base position happens to fall on (under tall detail the base positions of one
// feature spread over more than the feature, and a lift curving across that spread bent it).
// The foot is taken only within a quarter of the point's offset of a centre, and only where
// the base faces the same way (normals within 60 degrees): where the base curves inward under
// tall detail the base below the point can lie anywhere, and the point's own base position is
// the better guess. The centre is the point's own base position, moved towards the point right
// below the point (in the tangent plane of its base position) just far enough that it is
// within reach, so that the feet of a tall feature whose points drifted far sideways still lie
// under it. Otherwise the point stands on its own base position. Reconstruction turns a point
// by its foot's rotation and hangs it from its foot
// (reconstruction.cpp).
// base, base_normals, finest  #P by 3; rings from base_rings(base, parts, edit_ring_size).
// Returns #P base point indices.
IndexList base_feet(const Points& base, const Points& base_normals, const Points& finest, const IndexList& rings,
                    int ring_size);

// What edit_rotations found.
struct EditRotationReport {
  std::size_t unchanged = 0;  // rings the edit left as they were, to rounding: the identity
  std::size_t planar = 0;     // the rotation nearest to the ring's best map within its plane
  std::size_t curved = 0;     // rings with no clear plane: the best rotation of the ring (Kabsch)
  std::size_t on_a_line = 0;  // rings on a line, or turned over: the cluster's rotation
};

// The planes of the unedited rings, which no edit changes: what edit_rotations would find
// again on every call. kind: 1 a clear plane, 2 no clear plane, 3 on a line (RingKind).
// in_plane: for a clear plane, w1 and w2 with sum_j e1_j ((e0_j - mean e0) . w) the edited
// image of the plane's axes (least squares over the ring); zero otherwise.
struct EditRingPlanes {
  std::vector<Vec3> normals;  // #P
  std::vector<unsigned char> kind;  // #P
  std::vector<std::array<Vec3, 2>> in_plane;  // #P
  // How far a ring's edges may move and the ring still count as unchanged: the rounding of
  // the base's coordinates (1e-12 of its diagonal), well below any edit an artist makes.
  double tolerance = 0.0;
};
// ring_size at most edit_ring_size (std::invalid_argument otherwise), as for edit_rotations.
EditRingPlanes ring_planes(const Points& original, const IndexList& rings, int ring_size);

// original, edited   #P by 3, the stored base and the edited one
// rings              #P by ring_size, from base_rings(original, parts, edit_ring_size); ring_size
//                    at most edit_ring_size (std::invalid_argument otherwise)
// cluster_rotation   #C rotations of the level-0 clusters (transported_rotations), with
// labels             #P each point's level-0 cluster: they tell a ring that turned over from
//                    one that turned past 90 degrees, and stand in where a ring has no plane
//                    or turned over (a ring's plane 75-90 degrees from its cluster's turn
//                    blends the two, so the turn goes over to the cluster's continuously); a
//                    ring that kept its shape (a rigid turn, an isometric bend) keeps its own
//                    turn up to 150 degrees from its cluster's, going over to it by 170
// planes             ring_planes(original, rings, ring_size), or nullptr to find them here
// Returns #P rotations. A ring the edit did not change, to within 1e-12 of the base's
// diagonal, gives exactly the identity, so an unedited round trip stays exact.
std::vector<Mat3> edit_rotations(const Points& original, const Points& edited, const IndexList& rings,
                                 int ring_size, const std::vector<Mat3>& cluster_rotation, const IndexList& labels,
                                 const EditRingPlanes* planes = nullptr, EditRotationReport* report = nullptr);

// The same into `rotation`, reusing its storage (an editing session calls it over and over:
// fresh pages cost a fault per 4 KB on first touch). kinds, when not null, receives #P ring
// kinds (0 unchanged, 1 planar, 2 curved, 3 on a line: the report's four counts, per point).
void edit_rotations(const Points& original, const Points& edited, const IndexList& rings, int ring_size,
                    const std::vector<Mat3>& cluster_rotation, const IndexList& labels, const EditRingPlanes* planes,
                    std::vector<Mat3>& rotation, EditRotationReport* report = nullptr,
                    std::vector<unsigned char>* kinds = nullptr);

// The rotations of the listed points only, measured as edit_rotations measures them, into
// rotation and kinds (both #P, from an earlier call on the same model): an editing session's
// next edit measures again only the rings it moved. turned_again[j] becomes 1 where j's
// rotation changed, bit for bit (#P, left as it was elsewhere).
void edit_rotations_of(const IndexList& which, const Points& original, const Points& edited, const IndexList& rings,
                       int ring_size, const std::vector<Mat3>& cluster_rotation, const IndexList& labels,
                       const EditRingPlanes& planes, std::vector<Mat3>& rotation, std::vector<unsigned char>& kinds,
                       std::vector<unsigned char>& turned_again);

// The report's four counts from the kinds edit_rotations left.
EditRotationReport count_ring_kinds(const std::vector<unsigned char>& kinds);

}  // namespace pointscale
