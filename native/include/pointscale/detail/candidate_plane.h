// One iteration of the MLS projection (mls_projection.h) against a fixed candidate set: the
// weighted plane (Eq. 2-3) of the k candidates nearest to the current foot point. One kd-tree
// query serves a point's iterations (and often the next points, mls_projection.cpp), so the
// candidates are gathered once per point, structure-of-arrays and relative to the projected
// point, and every iteration is a few vectorised passes over them.
#pragma once
#include <vector>

#include "pointscale/detail/plane_fit.h"
#include "pointscale/types.h"

namespace pointscale {

struct CandidateSet {
  std::vector<double> x, y, z;  // #C offsets from the projected point
  std::vector<double> inv_h2;   // #C 1 / h^2 of each candidate's kernel
  std::vector<double> h;        // #C kernel widths
  std::vector<double> extra;    // #C added to the squared distance in the weight (thin sheets), or 0
  std::vector<double> r2, e;    // #C workspace
  // The k nearest of the last fit on this set (1 or 0 per candidate), and how many: usually the
  // k nearest of the next fit too, which two vector passes confirm without a selection.
  std::vector<double> last_nearest;
  int last_count = 0;
  int size = 0;

  void resize(int count);
};

// The plane of the k candidates nearest to foot (an offset from the projected point), with
// Gaussian weights exp(-(|c_j - foot|^2 + extra_j) / h_j^2) scaled so that the largest is 1,
// exactly as fit_weighted_plane over gaussian_weights. fit.mean is an offset from the projected
// point too. nearest_h receives the kernel width of the nearest candidate, kth_d2 the squared
// distance of the k-th nearest.
PlaneFit fit_nearest_plane(CandidateSet& candidates, int k, const Vec3& foot, double& nearest_h, double& kth_d2);

}  // namespace pointscale
