// The cubic step the blends between two behaviours use, so that nothing jumps where one gives
// way to the other.
#pragma once
#include <algorithm>

namespace pointscale {

// 0 at or below from, 1 at or above to, smooth in between (3 t^2 - 2 t^3).
inline double smooth_step(double x, double from, double to) {
  const double t = std::clamp((x - from) / (to - from), 0.0, 1.0);
  return t * t * (3.0 - 2.0 * t);
}

}  // namespace pointscale
