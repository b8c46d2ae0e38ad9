// Level normals that stand nearly at right angles to their orientation reference, eased towards
// it, so that the side they take does not flip in one step.
#pragma once

#include "pointscale/types.h"

namespace pointscale {

// A normal's side is the one its reference points to (support_normals). Where gains other
// than 1 turn a level's shape far from the unit gains' (a spike raised at the tip of a nose),
// a refitted normal can reach right angles to its reference, and there its side is a toss-up:
// a gain changed by 1e-12 turned a band's offset over and moved a point 2.7% of the model.
// Each normal within side_flip_band of right angles (cosine to its reference below it) is
// moved towards the reference's direction, all the way at right angles and not at all at the
// band's edge, with a smooth step between: both sides of a flip meet at the reference, so the
// points move continuously with the gains. At unit gains a level's normals lie within 90
// degrees of the level's below, so within 45 of the reference the reconstruction sums from
// them, and the band leaves them alone.
// normals    #P by 3 unit normals, each with normals.row(i) . reference.row(i) >= 0, eased in place
// reference  #P by 3 orientation references (any length; a zero row leaves its normal alone)
constexpr double side_flip_band = 0.26;  // cos(75 degrees)
void ease_side_flips(Points& normals, const Points& reference);

}  // namespace pointscale
