#include "pointscale/detail/align_level.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numeric>
#include <vector>

#include "pointscale/parallel.h"
#include "pointscale/detail/level_normals.h"
#include "pointscale/detail/plane_fit.h"
#include "pointscale/detail/wake_list.h"

namespace pointscale {

namespace {

constexpr double never = std::numeric_limits<double>::infinity();

// The foot of f in the plane through p with unit normal n: where p moves so that f - p lies
// along n.
Vec3 tangent_foot(const Vec3& f, const Vec3& p, const Vec3& n) { return f - (f - p).dot(n) * n; }

// The next damping of one anchor. full: its move now; last: its move before; cap: the largest
// damping it may regain (1, or its Newton step).
double next_damping(const DampingPolicy& policy, double damping, double full, double last, double cap) {
  if (full > policy.swing * last) return std::max(damping * 0.5, policy.floor);
  if (policy.regain_unless_swing || full < last) return std::min(cap, damping * policy.regain);
  return damping;
}

// Moves p along the unit direction d onto the MLS surface: two ray-plane steps (Adamson and
// Alexa 2003), enough for a point that slid a little off it within its tangent plane.
Vec3 along_onto(const Vec3& p, const Vec3& d, const SpatialIndex& surface, const Eigen::VectorXd& h, int k) {
  k = std::min<int>(k, surface.size());
  Index idx[64];
  double d2[64], ih2[64], w[64];
  k = std::min(k, 64);
  Vec3 x = p;
  for (int it = 0; it < 2; ++it) {
    const int found = surface.knn(x.data(), k, idx, d2);
    for (int j = 0; j < found; ++j) ih2[j] = 1.0 / (h(idx[j]) * h(idx[j]));
    gaussian_weights(d2, ih2, found, w);
    const PlaneFit fit = fit_weighted_plane(surface.points(), idx, w, found, x);
    const double cosine = fit.ok ? fit.normal.dot(d) : 0.0;
    if (std::abs(cosine) < 0.5) return x;  // the surface turns away here: stay
    x += ((fit.mean - x).dot(fit.normal) / cosine) * d;
  }
  return x;
}

// The per-anchor state of the iteration.
struct AnchorSteps {
  std::vector<double> moves, damping, cap, earlier;
  std::vector<unsigned char> frozen;  // pinned or kept: no longer moved
  explicit AnchorSteps(Index clusters)
      : moves(static_cast<std::size_t>(clusters), never), damping(static_cast<std::size_t>(clusters), 1.0),
        cap(static_cast<std::size_t>(clusters), 1.0), earlier(static_cast<std::size_t>(clusters), never),
        frozen(static_cast<std::size_t>(clusters), 0) {}
};

// Each anchor's Newton step. Moving an anchor by u turns its normal by about u x curvature and
// its target by detail x curvature x u the other way: 1 / (1 + |detail| x curvature), with the
// curvature from the normals of the neighbouring anchors.
std::vector<double> newton_steps(const Points& fine, const Points& level, const LevelSupport& support,
                                 const Points& anchor_reference) {
  const Index c_count = support.clusters;
  std::vector<Index> own(static_cast<std::size_t>(c_count));
  std::iota(own.begin(), own.end(), 0);
  const Points anchors = support_centroids(level, support);
  const Points normals = support_normals(anchors, own.data(), anchors, support, anchor_reference);
  const int k = support.neighbors;
  std::vector<double> out(static_cast<std::size_t>(c_count));
  for (Index c = 0; c < c_count; ++c) {
    // A ratio of sums: nearly coincident anchors must not blow the estimate up.
    double turn = 0.0, span = 0.0;
    const Index* nb = support.neighborhoods.data() + static_cast<std::size_t>(c) * k;
    for (int j = 1; j < k; ++j) {
      span += (anchors.row(nb[j]) - anchors.row(c)).norm();
      turn += (normals.row(nb[j]) - normals.row(c)).norm();
    }
    const double curvature = span > 0 ? turn / span : 0.0;
    const double detail = (fine.row(support.anchors[c]) - level.row(support.anchors[c])).norm();
    out[c] = 1.0 / (1.0 + detail * curvature);
  }
  return out;
}

// How far point i of cluster c may slide: its cluster's kernel width, or a twentieth of its
// offset (a 3 degree turn of its normal line), whichever is more. The level leaves the base by
// move^2 curvature / 2.
double reach(const Points& fine, const Points& start, const LevelSupport& support, Eigen::Index i, Index c) {
  return std::max(support.h(c), 0.05 * (fine.row(i) - start.row(i)).norm());
}

}  // namespace

LevelAligner::LevelAligner(const Points& fine, Points& level, const LevelSupport& support, const AlignPolicy& policy)
    : fine_(fine), level_(level), support_(support), policy_(policy) {
  if (policy_.keep_out_of_reach) start_ = level;
}

AnchorAlignment LevelAligner::align_anchors(const Points& anchor_reference, double stop, int max_iterations,
                                            const ProgressStage& stage) {
  const Points& fine = fine_;
  Points& level = level_;
  const LevelSupport& support = support_;
  const AlignPolicy& policy = policy_;
  AnchorSteps steps(support.clusters);
  if (policy.newton_start) {
    steps.damping = newton_steps(fine, level, support, anchor_reference);
    steps.cap = steps.damping;
  }
  WakeList wake(policy.wake_list ? support.clusters : 0);
  std::vector<Index> todo;
  Points anchors = support_centroids(level, support);  // kept equal to the anchors' rows of level
  // The rounds that progress expects: with pinning, a few.
  const double rounds = policy.pin_unsettled ? 4.0 : 1.0;

  // Moves the anchors in todo one damped step towards fine's foot on their normal line.
  auto step_anchors = [&]() {
    Points query(static_cast<Eigen::Index>(todo.size()), 3), query_reference(query.rows(), 3);
    for (std::size_t j = 0; j < todo.size(); ++j) {
      query.row(j) = anchors.row(todo[j]);
      query_reference.row(j) = anchor_reference.row(todo[j]);
    }
    // Only the listed anchors' normals: each row is the one support_normals would give over all
    // of them (a cluster's fit never sees the other queries), so sweeping a subset is exact.
    const Points normals = support_normals_of(query, todo, anchors, support, query_reference);
    parallel_for(todo.size(), [&](std::size_t b, std::size_t e) {
      for (std::size_t j = b; j < e; ++j) {
        const Index c = todo[j];
        const Index i = support.anchors[c];
        const Vec3 nrm = normals.row(static_cast<Eigen::Index>(j)).transpose();
        const Vec3 f = fine.row(i).transpose();
        const Vec3 p = level.row(i).transpose();
        const Vec3 move = tangent_foot(f, p, nrm) - p;
        const double full = move.norm();
        // A growing move means the step is too long: halve it; a shrinking one regains it.
        steps.damping[c] = next_damping(policy.damping, steps.damping[c], full, steps.moves[c], steps.cap[c]);
        steps.moves[c] = full;
        const Vec3 slid = p + steps.damping[c] * move;
        // A slide m leaves the surface by about m^2 curvature / 2: only larger ones need the step back.
        const bool back = policy.surface && steps.damping[c] * full > 1e-3 * support.h(static_cast<Eigen::Index>(c));
        level.row(i) = (back ? along_onto(slid, nrm, *policy.surface, *policy.surface_h, policy.surface_neighbors)
                             : slid).transpose();
        if (policy.keep_out_of_reach &&
            (level.row(i) - start_.row(i)).norm() > reach(fine, start_, support, i, support.labels[i])) {
          level.row(i) = start_.row(i);
          steps.frozen[c] = 1;
          steps.moves[c] = 0.0;
        }
        anchors.row(c) = level.row(i);
      }
    });
  };

  // After a round that did not settle: pins the anchors that stopped settling over its second
  // half (all unsettled ones after a few rounds) to their finer position, so that the others
  // settle around them. Anchors that still converge keep going, and from round 8 on every
  // round pins at least one, so the rounds end.
  auto pin_unsettled = [&](int round) {
    const bool last_chance = round >= 8;
    for (Index c = 0; c < support.clusters; ++c)
      if (!steps.frozen[c] && steps.moves[c] > stop && steps.moves[c] < never &&
          (last_chance || steps.moves[c] > 0.25 * steps.earlier[c])) {
        steps.frozen[c] = 1;
        level.row(support.anchors[c]) = fine.row(support.anchors[c]);
        anchors.row(c) = level.row(support.anchors[c]);
      }
  };

  AnchorAlignment out;
  for (int round = 0;; ++round) {
    double largest = 0.0;
    bool settled = false;
    for (int it = 0; it < max_iterations; ++it, ++out.iterations) {
      stage.report(std::min(1.0, static_cast<double>(out.iterations) / (rounds * max_iterations)));
      if (policy.pin_unsettled && it == max_iterations / 2) steps.earlier = steps.moves;
      bool sweep = true;
      if (policy.wake_list) {
        sweep = wake.next(steps.frozen, todo);
      } else {
        todo.clear();
        for (Index c = 0; c < support.clusters; ++c) if (!steps.frozen[c]) todo.push_back(c);
      }
      step_anchors();
      largest = 0.0;
      if (policy.wake_list) wake.clear();
      for (const Index c : todo) {
        if (!(steps.moves[c] > stop)) continue;
        largest = std::max(largest, steps.moves[c]);
        if (policy.wake_list) wake.wake_neighbourhood(support, c);
      }
      if (largest <= stop && sweep) {
        settled = true;
        if (policy.count_settling_iteration) ++out.iterations;
        break;
      }
      // A neighbour woken by another's move starts afresh: its small old move is no measure.
      if (policy.wake_list)
        for (const Index c : wake.woken()) if (steps.moves[c] <= stop) steps.moves[c] = never;
    }
    out.residual = largest;
    if (settled || !policy.pin_unsettled) break;
    pin_unsettled(round);
    std::fill(steps.moves.begin(), steps.moves.end(), never);
    wake.wake_all();
  }
  for (const unsigned char f : steps.frozen) out.frozen += f;
  return out;
}

std::size_t LevelAligner::align_others(const Points& normals) {
  std::vector<unsigned char> is_anchor(static_cast<std::size_t>(level_.rows()), 0), stays(is_anchor.size(), 0);
  for (Index a : support_.anchors) is_anchor[a] = 1;
  parallel_for(static_cast<std::size_t>(level_.rows()), [&](std::size_t b, std::size_t e) {
    for (std::size_t ii = b; ii < e; ++ii) {
      if (is_anchor[ii]) continue;
      const Eigen::Index i = static_cast<Eigen::Index>(ii);
      const Vec3 nrm = normals.row(i).transpose();
      const Vec3 foot = tangent_foot(fine_.row(i).transpose(), level_.row(i).transpose(), nrm);
      // Written as "not within reach" so that a NaN distance keeps the point too.
      if (policy_.keep_out_of_reach &&
          !((foot - start_.row(i).transpose()).norm() <= reach(fine_, start_, support_, i, support_.labels[ii]))) {
        stays[ii] = 1;
        continue;
      }
      level_.row(i) = (policy_.surface ? along_onto(foot, nrm, *policy_.surface, *policy_.surface_h, policy_.surface_neighbors)
                                       : foot).transpose();
    }
  });
  std::size_t kept = 0;
  for (const unsigned char s : stays) kept += s;
  return kept;
}

}  // namespace pointscale
