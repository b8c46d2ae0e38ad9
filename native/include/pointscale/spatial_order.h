// A processing order in which consecutive points are near each other (Z-order, Morton code on a
// 2^21 grid over the bounding box). Loops that query a kd-tree per point run several times
// faster in this order than in a random one: the tree nodes and support points they touch stay
// in cache. The points themselves are not moved; only the loop visits them in this order.
#pragma once
#include "pointscale/types.h"

namespace pointscale {

// points #P by 3; returns #P indices into points.
IndexList morton_order(const Points& points);

}  // namespace pointscale
