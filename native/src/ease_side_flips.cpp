#include "pointscale/detail/ease_side_flips.h"

#include "pointscale/detail/smooth_step.h"
#include "pointscale/parallel.h"

namespace pointscale {

void ease_side_flips(Points& normals, const Points& reference) {
  parallel_for(static_cast<std::size_t>(normals.rows()), [&](std::size_t b, std::size_t e) {
    for (std::size_t ii = b; ii < e; ++ii) {
      const Eigen::Index i = static_cast<Eigen::Index>(ii);
      const Vec3 r = reference.row(i).transpose();
      const double length = r.norm();
      if (!(length > 0.0)) continue;
      const Vec3 n = normals.row(i).transpose();
      const double c = n.dot(r) / length;
      if (!(c < side_flip_band)) continue;
      const double weight = smooth_step(c, 0.0, side_flip_band);
      const Vec3 eased = (1.0 - weight) * (r / length) + weight * n;  // within 90 degrees: never zero
      normals.row(i) = eased.normalized().transpose();
    }
  }, {}, 4096);
}

}  // namespace pointscale
