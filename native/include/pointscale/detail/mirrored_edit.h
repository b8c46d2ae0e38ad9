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
// A mirror moves every cluster and reverses every one that can tell: where enough clusters tell,
// the part is mirrored when nine in ten of those say reversed and at most one in twenty of all
// its clusters was left alone, so a dent that presses a cap through a plane is no mirror of it.
// Votes count where neighbourhoods are local (ten times as many clusters in the part as a
// neighbourhood holds); a part with fewer level-0 clusters whose votes there and whose anchors'
// best map say reversed votes at the first finer level with that many, from the base positions
// of that level's anchors. A part that cannot tell (nearly flat: a plate, a relief, a terrain)
// is mirrored only when its anchors are a mirror of the stored ones to within rounding: a mirror
// across its own plane looks like a half turn or a pressed dimple, and the fit of its thin
// direction follows any warp. A flat part has no orientation at all.
// original, edited  #P by 3; support: the model's levels' supports (level 0 first); parts: #P
// part labels (connected_parts.h), or empty for one part; vote: level 0's orientation votes,
// from transported_rotations(original, edited, support[0], &vote).
// Returns #P flags (1: mirrored), or an empty list when no part is mirrored.
std::vector<unsigned char> mirrored_points(const Points& original, const Points& edited,
                                           const std::vector<LevelSupport>& support, const IndexList& parts,
                                           const std::vector<signed char>& vote);

// The fixed reflection (x to -x) of the flagged rows of p, in place: its own inverse.
void reflect_rows(Points& p, const std::vector<unsigned char>& flags);

}  // namespace pointscale
