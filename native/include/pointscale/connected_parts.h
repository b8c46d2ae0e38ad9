// The connected parts of a mesh, so that a decomposition can keep them apart: eyes, teeth and
// clothing layers are separate parts of one mesh, and a point-based fit would blend them.
#pragma once
#include "pointscale/types.h"

namespace pointscale {

struct Parts {
  IndexList labels;  // #P the part of each point, numbered in the order of each part's lowest paired vertex
  Index count = 0;
};

// points  #P by 3
// pairs   #E by 2 vertex indices, row-major: a mesh's edges, or each face's corners as pairs
// A vertex in no pair says nothing about where it belongs (a scan's untriangulated point, a
// loose vertex): it joins the part of the nearest vertex that is in a pair. With no pairs at
// all every point is in one part.
Parts connected_parts(const Points& points, const IndexList& pairs);

// For every point, its k nearest points of its own part, itself first: #P by k row-major. A
// part of fewer than k points fills the rest of each of its rows with the point itself.
// points  #P by 3; parts  #P labels in [0, count); throws std::invalid_argument otherwise,
// or for k < 1
IndexList knn_within_parts(const Points& points, const IndexList& parts, int k);

}  // namespace pointscale
