// Edits that mirror the base (reconstruction.cpp). An artist who mirrors a model's coarse
// shape (a scale of -1 on Level 0 in Blender, or a mirror across any plane) expects its
// detail mirrored with it. The turns an edit gives the detail are rotations, and no rotation
// is a mirror: ring by ring, a mirrored base reads as turned over, and the detail came out on
// the inside. Reconstruction therefore mirrors such a part once more, by a fixed reflection,
// which leaves it a proper (orientation-keeping) edit of the stored base, builds it there, and
// mirrors the result back.
#pragma once
#include <vector>

#include "pointscale/level_support.h"
#include "pointscale/types.h"

namespace pointscale {

// Which points lie in a part the edit mirrors. Each level-0 cluster's neighbourhood votes: the
// edit keeps its orientation or reverses it (its best orthogonal map's determinant), or it
// cannot tell (a nearly flat neighbourhood), or the edit left it alone. Orientation is local,
// so a bend that rolls a part round on itself (whose best linear map as a whole can reverse)
// keeps it, while a mirror with an uneven scale, or with a sculpted surface on it, reverses it.
// A mirror moves every cluster and reverses every one that can tell: a part with local
// neighbourhoods (three times as many clusters as a neighbourhood holds) where a quarter of its
// clusters tell is mirrored when nine in ten of those say reversed and at most one in twenty of
// all its clusters was left alone, so a dent that presses a cap through a plane is no mirror of
// the part. A part too flat for that (a plate, a relief, a terrain), or with a handful of
// clusters, is judged from its anchors as a whole: a mirror across a plane that cuts across it
// counts when the part's best linear map reverses and explains the edit to 1% (so a brush or a
// smoothing on top is allowed), and a mirror across the part's own plane, which a half turn or
// a dimple pressed through it resembles, only to within rounding. A flat part has no
// orientation at all. Last, a part with more than one point in twenty left where it was is no
// mirror: a dent pressed a cap of it through a plane (a handful of anchors may all lie in it).
// original, edited  #P by 3; level0: the model's level-0 support; parts: #P part labels
// (connected_parts.h), or empty for one part; vote: the clusters' orientation votes, from
// transported_rotations(original, edited, level0, &vote).
// Returns #P flags (1: mirrored), or an empty list when no part is mirrored.
std::vector<unsigned char> mirrored_points(const Points& original, const Points& edited, const LevelSupport& level0,
                                           const IndexList& parts, const std::vector<signed char>& vote);

// The fixed reflection (x to -x) of the flagged rows of p, in place: its own inverse.
void reflect_rows(Points& p, const std::vector<unsigned char>& flags);

}  // namespace pointscale
