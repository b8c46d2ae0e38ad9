// Orientation from a base surface's samples (encode_onto, morph).
#pragma once
#include "pointscale/spatial_index.h"

namespace pointscale {

// Unit normals of the base samples, oriented outward by propagation (#B by 3).
Points oriented_normals(const SpatialIndex& base);

// Per query point, the oriented normal of its nearest base sample: #Q by 3 orientation references.
Points nearest_normals(const Points& query, const SpatialIndex& base, const Points& base_normals);

}  // namespace pointscale
