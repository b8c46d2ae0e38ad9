// Whether a base handed over in world coordinates is the model's own: stored + origin exactly,
// as the package hands the stored base out (an IEEE sum, the same in NumPy and here). Centring
// it again would round it off the stored base, and an edit of no size would cost a whole
// edited pass; reconstruct's binding and Reconstructor both ask this before centring.
#pragma once
#include <cstddef>

#include "pointscale/types.h"

namespace pointscale {

// world   #P by 3, row-major, in the caller's point order
// stored  #P by 3, the model's base (about the origin)
// order   #P: stored row r is world row order[r]; nullptr for the same order
// Stops at the first coordinate that differs.
inline bool is_stored_base(const double* world, const Points& stored, const Vec3& origin,
                           const Index* order = nullptr) {
  for (Eigen::Index r = 0; r < stored.rows(); ++r) {
    const double* v = world + 3 * static_cast<std::size_t>(order ? order[r] : r);
    for (int c = 0; c < 3; ++c)
      if (!(v[c] == stored(r, c) + origin(c))) return false;
  }
  return true;
}

}  // namespace pointscale
