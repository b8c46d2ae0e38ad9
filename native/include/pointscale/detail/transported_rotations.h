// The coarse turn of an edited level 0, per cluster of its support (reconstruction.cpp).
#pragma once
#include <vector>

#include "pointscale/level_support.h"

namespace pointscale {

// The coarse turn of an edited level 0: the rotation per cluster that best maps the cluster's
// neighbourhood onto the edited one (Kabsch). edit_rotations takes it where a ring has no
// plane, and to tell a ring that turned past 90 degrees from one that folded over. A
// neighbourhood the edit left as it was gives exactly the identity.
// original, edited  #P by 3. Returns #C rotations.
std::vector<Mat3> transported_rotations(const Points& original, const Points& edited, const LevelSupport& support);

}  // namespace pointscale
