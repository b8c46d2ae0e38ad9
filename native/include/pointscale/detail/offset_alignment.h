// What the two offset aligners share, make_offsets_normal (decompose) and align_offsets
// (encode_onto). Both make fine - level lie along the level's recomputed normals: the anchors,
// on whose positions alone the normals depend, move by damped steps towards the foot of their
// fine point in their tangent plane; then every other point moves there in one step, exact by
// construction since its normal does not depend on it. Their damping and their pinning differ
// (decompose pins an anchor that does not settle to its finer position and iterates only the
// anchors that can still move; encode keeps a point whose consistent position is out of reach
// where it was, and steps back onto the base's surface), so each keeps its own schedule and
// numbers, and its results.
#pragma once
#include <algorithm>
#include <vector>

#include "pointscale/detail/level_normals.h"
#include "pointscale/parallel.h"

namespace pointscale {

// How an anchor's step is damped: halved while its move grows (a swing), regained while it
// shrinks.
struct DampingPolicy {
  double swing = 1.0;          // a move above swing x the last one counts as a swing
  double floor = 1.0 / 64.0;   // the step never falls below this fraction
  double regain = 1.5;         // factor by which the step grows back
  // true: any move that is no swing regains the step; false: only a move smaller than the last.
  bool regain_unless_swing = true;
};

// The next damping of one anchor. full: its move now; last: its move before; cap: the largest
// damping it may regain (1, or a Newton step).
inline double next_damping(const DampingPolicy& policy, double damping, double full, double last, double cap) {
  if (full > policy.swing * last) return std::max(damping * 0.5, policy.floor);
  if (policy.regain_unless_swing || full < last) return std::min(cap, damping * policy.regain);
  return damping;
}

// The foot of f in the plane through p with unit normal n: where p moves so that f - p lies
// along n.
inline Vec3 tangent_foot(const Vec3& f, const Vec3& p, const Vec3& n) { return f - (f - p).dot(n) * n; }

// The last step of both: each point that is not an anchor goes to place(i, foot, n) (normals
// #P by 3, the level's, fitted once the anchors have settled); then visit(i, f, n) sees every
// point, anchors included.
template <class Place, class Visit>
void step_non_anchors(const Points& fine, Points& level, const Points& normals, const LevelSupport& support,
                      const Place& place, const Visit& visit) {
  std::vector<unsigned char> is_anchor(static_cast<std::size_t>(level.rows()), 0);
  for (Index a : support.anchors) is_anchor[a] = 1;
  parallel_for(static_cast<std::size_t>(level.rows()), [&](std::size_t b, std::size_t e) {
    for (std::size_t ii = b; ii < e; ++ii) {
      const Eigen::Index i = static_cast<Eigen::Index>(ii);
      const Vec3 nrm = normals.row(i).transpose();
      const Vec3 f = fine.row(i).transpose();
      if (!is_anchor[ii]) place(i, tangent_foot(f, level.row(i).transpose(), nrm), nrm);
      visit(i, f, nrm);
    }
  });
}

}  // namespace pointscale
