// The coarse turn of an edited level 0, per cluster of its support (reconstruction.cpp).
#pragma once
#include <Eigen/SVD>
#include <vector>

#include "pointscale/level_support.h"

namespace pointscale {

// The coarse turn of an edited level 0: the rotation per cluster that best maps the cluster's
// neighbourhood onto the edited one (Kabsch). edit_rotations takes it where a ring has no
// plane, and to tell a ring that turned past 90 degrees from one that folded over. A
// neighbourhood the edit left as it was gives exactly the identity.
// original, edited  #P by 3. Returns #C rotations.
// orientation: if given, receives #C votes of whether the edit keeps (+1) or reverses (-1) the
// orientation of each cluster's neighbourhood (its best orthogonal map's determinant), cannot
// tell (0: the neighbourhood spreads across its plane by less than 1% of its spread along it,
// where a lift can turn the sign of its thinnest direction's fit, and a mirror across the
// plane moves it as a half turn does), or left it alone (2) (mirrored_edit.h).
std::vector<Mat3> transported_rotations(const Points& original, const Points& edited, const LevelSupport& support,
                                        std::vector<signed char>* orientation = nullptr);

// Cluster c's neighbourhood between two sets of the level's anchor positions (b0, b1: #C by 3,
// support_centroids): into cov the weighted cross sums, sum w e0 e1^T, with w = exp(-|e0|^2 / h^2)
// over the neighbours' edges e from the cluster's anchor. False, cov untouched, where no anchor
// of the neighbourhood moved.
bool neighbourhood_cross(const Points& b0, const Points& b1, const LevelSupport& support, Index c, Mat3& cov);

// The orientation vote of a neighbourhood from its cross sums' SVD (full U and V): 1 kept, -1
// reversed, 0 cannot tell (spread across its plane under 1% of its spread along it, or on a line).
signed char orientation_vote(const Eigen::JacobiSVD<Mat3>& svd);

}  // namespace pointscale
