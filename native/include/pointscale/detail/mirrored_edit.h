// Edits that mirror the base (reconstruction.cpp). An artist who mirrors a model's coarse
// shape (a scale of -1 on Level 0 in Blender, or a mirror across any plane) expects its
// detail mirrored with it. The turns an edit gives the detail are rotations, and no rotation
// is a mirror: ring by ring, a mirrored base reads as turned over, and the detail came out on
// the inside. Reconstruction therefore mirrors such a part once more, by a fixed reflection,
// which leaves it a proper (orientation-keeping) edit of the stored base, builds it there, and
// mirrors the result back.
#pragma once
#include <vector>

#include "pointscale/types.h"

namespace pointscale {

// Which points lie in a part the edit mirrors: the part's best mirror-similarity (a mirror,
// a turn and a uniform scale, fitted about the centroids) fits the edited base at least four
// times better than its best similarity without the mirror. A flat part has no such fit (a
// mirror across its own plane moves it as a turn by 180 degrees does), nor has an edit far from
// any similarity: such parts count as not mirrored.
// original, edited  #P by 3; parts: #P part labels (connected_parts.h), or empty for one part
// sample            mirror_sample(original, parts): the points the fits read
// Returns #P flags (1: mirrored), or an empty list when no part is mirrored.
std::vector<unsigned char> mirrored_points(const Points& original, const Points& edited, const IndexList& parts,
                                           const IndexList& sample);

// The points the fits read: about 4096 of each part, chosen by their stored positions alone,
// so that the check costs no more on a large model. Found with the rest of what an edit needs
// (EditSupport) and renumbered with it, so a model in another point order (a Reconstructor's)
// sums the same points in the same order and decides alike, bit for bit.
IndexList mirror_sample(const Points& original, const IndexList& parts);

// The fixed reflection (x to -x) of the flagged rows of p, in place: its own inverse.
void reflect_rows(Points& p, const std::vector<unsigned char>& flags);

}  // namespace pointscale
