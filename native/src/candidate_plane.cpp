#include "pointscale/detail/candidate_plane.h"

#include <algorithm>
#include <limits>

#include "pointscale/detail/fast_exp.h"
#include "pointscale/detail/moment_lanes.h"
#include "pointscale/detail/simd_clones.h"

namespace pointscale {

void CandidateSet::resize(int count) {
  size = count;
  for (auto* v : {&x, &y, &z, &inv_h2, &h, &extra, &r2, &e, &last_nearest}) v->resize(static_cast<std::size_t>(count));
  last_count = 0;
}

POINTSCALE_CLONES
PlaneFit fit_nearest_plane(CandidateSet& c, int k, const Vec3& foot, double& nearest_h, double& kth_d2) {
  const int n = c.size;
  k = std::min(k, n);
  const double fx = foot.x(), fy = foot.y(), fz = foot.z();
  const double* __restrict px = c.x.data();
  const double* __restrict py = c.y.data();
  const double* __restrict pz = c.z.data();
  double* __restrict r2 = c.r2.data();
#pragma omp simd
  for (int j = 0; j < n; ++j) {
    const double dx = px[j] - fx, dy = py[j] - fy, dz = pz[j] - fz;
    r2[j] = dx * dx + dy * dy + dz * dz;
  }
  // The k nearest are known without a selection when every one of a guessed set of k is
  // nearer than every other candidate: first the last fit's k nearest (the foot moves little
  // between fits, and the next point of a query starts near the last), then the first k (the
  // candidates come sorted by distance from their query's centre, usually near the foot).
  double limit = 0.0;  // candidates with r2 <= limit take part: the k-th smallest r2
  bool prefix = false, known = false;
  if (c.last_count == k) {
    const double* __restrict in = c.last_nearest.data();
    double inner = 0.0, outer = std::numeric_limits<double>::infinity();
#pragma omp simd reduction(max : inner) reduction(min : outer)
    for (int j = 0; j < n; ++j) {
      const double member = in[j] > 0.0 ? r2[j] : 0.0;
      const double other = in[j] > 0.0 ? std::numeric_limits<double>::infinity() : r2[j];
      inner = member > inner ? member : inner;
      outer = other < outer ? other : outer;
    }
    if (inner < outer) { limit = inner; known = true; }
  }
  if (!known) {
    double inner = 0.0, outer = std::numeric_limits<double>::infinity();
#pragma omp simd reduction(max : inner)
    for (int j = 0; j < k; ++j) inner = r2[j] > inner ? r2[j] : inner;
#pragma omp simd reduction(min : outer)
    for (int j = k; j < n; ++j) outer = r2[j] < outer ? r2[j] : outer;
    limit = inner;
    prefix = inner < outer;
    if (!prefix) {
      // The k-th smallest lies in [outer, inner]; the values below outer are all among the first
      // k, so it is the (k - below)-th smallest of the few values in that range (a short
      // selection over them, not a general one over all candidates).
      double* __restrict in_range = c.e.data();  // free until the weights below
      int below = 0, m_in = 0;
      for (int j = 0; j < n; ++j) {
        const double v = r2[j];
        below += v < outer;
        in_range[m_in] = v;
        m_in += v >= outer && v <= inner;
      }
      std::nth_element(in_range, in_range + (k - below - 1), in_range + m_in);
      limit = in_range[k - below - 1];
    }
  }
  {
    double* __restrict in = c.last_nearest.data();
    int count = 0;
#pragma omp simd reduction(+ : count)
    for (int j = 0; j < n; ++j) {
      in[j] = r2[j] <= limit ? 1.0 : 0.0;
      count += r2[j] <= limit;
    }
    c.last_count = count;
  }
  kth_d2 = limit;
  const int m = prefix ? k : n;  // with the prefix, the rest need not be looked at
  const double* __restrict ih2 = c.inv_h2.data();
  const double* __restrict extra = c.extra.data();
  double* __restrict e = c.e.data();
  double min_e = std::numeric_limits<double>::infinity();
  // The kernel width of the nearest candidate (the first, among equals): a vector minimum, then
  // a scan for it. (A running argmin in one loop stored through nearest_h at every new minimum.)
  double nearest = std::numeric_limits<double>::infinity();
#pragma omp simd reduction(min : nearest)
  for (int j = 0; j < m; ++j) nearest = r2[j] < nearest ? r2[j] : nearest;
  int at = 0;
  while (at < m && !(r2[at] == nearest)) ++at;
  nearest_h = c.h[static_cast<std::size_t>(at < m ? at : 0)];
#pragma omp simd reduction(min : min_e)
  for (int j = 0; j < m; ++j) {
    e[j] = (r2[j] + extra[j]) * ih2[j];
    const double masked = r2[j] <= limit ? e[j] : std::numeric_limits<double>::infinity();
    min_e = masked < min_e ? masked : min_e;
  }
  // Candidates in fixed lanes (moment_lanes.h): the same sums on every CPU.
  MomentLanes s;
  const auto add = [&](int j, int l) POINTSCALE_ALWAYS_INLINE_LAMBDA {
    const double w = r2[j] <= limit ? exp_nonpositive(min_e - e[j]) : 0.0;
    const double dx = px[j] - fx, dy = py[j] - fy, dz = pz[j] - fz;
    const double wx = w * dx, wy = w * dy, wz = w * dz;
    s.add(l, w, wx, wy, wz, wx * dx, wy * dy, wz * dz, wx * dy, wx * dz, wy * dz);
  };
  int j = 0;
  for (; j + moment_lanes <= m; j += moment_lanes) {
#pragma omp simd
    for (int l = 0; l < moment_lanes; ++l) add(j + l, l);
  }
  for (int l = 0; j + l < m; ++l) add(j + l, l);
  return plane_from_sums(lanes_total(s.w), Vec3(lanes_total(s.x), lanes_total(s.y), lanes_total(s.z)),
                         lanes_total(s.xx), lanes_total(s.yy), lanes_total(s.zz), lanes_total(s.xy),
                         lanes_total(s.xz), lanes_total(s.yz), foot);
}

}  // namespace pointscale
