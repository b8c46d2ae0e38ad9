// A processing order in which consecutive points are near each other (Z-order, Morton code on a
// 2^21 grid over the bounding box). Loops that query a kd-tree per point run faster in this
// order than in a random one, since the tree nodes and support points they touch stay in
// cache. The points themselves are not moved; only the loop visits them in this order.
#pragma once
#include <vector>

#include "pointscale/types.h"

namespace pointscale {

// points #P by 3; returns #P indices into points.
IndexList morton_order(const Points& points);

// The inverse permutation: out[order[t]] = t, the place of each index in order (#P, a
// permutation of 0..#P-1).
IndexList inverse_order(const IndexList& order);

// The indices 0..#P-1 grouped by label (a counting sort): group c is
// members[offsets[c] .. offsets[c + 1]), in index order, or in the order of `visit` (#P, a
// permutation of 0..#P-1) when given. Taken in full, members is a spatial order when the labels
// are (decimation clusters are numbered along their split tree).
// labels #P, each in [0, count).
struct LabelGroups {
  std::vector<Index> offsets;  // #count + 1
  IndexList members;           // #P
};
LabelGroups group_by_label(const Index* labels, std::size_t n, Index count, const Index* visit = nullptr);

}  // namespace pointscale
