#include "pointscale/detail/make_offsets_normal.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numeric>
#include <vector>

#include "pointscale/parallel.h"
#include "pointscale/detail/release_memory.h"
#include "pointscale/detail/offset_alignment.h"
#include "pointscale/detail/level_normals.h"

namespace pointscale {

namespace {

constexpr double never = std::numeric_limits<double>::infinity();

// Halve the step while the move grows, down to 1/64, and regain it by half again otherwise.
constexpr DampingPolicy decompose_damping{1.0, 1.0 / 64.0, 1.5, true};

// The anchors to move next: only anchors that moved, or whose neighbours moved, can move again.
// Flagged in `active` and listed in `woken`, so that an iteration costs in proportion to them:
// a real scan takes hundreds of iterations over a few anchors each.
class WakeList {
 public:
  explicit WakeList(Index clusters) : active_(static_cast<std::size_t>(clusters), 0) { wake_all(); }

  void wake_all() {
    woken_.resize(active_.size());
    std::iota(woken_.begin(), woken_.end(), 0);
    std::fill(active_.begin(), active_.end(), 1);
  }

  // Lists the woken anchors that are not pinned, in order, into todo; once none is left, every
  // anchor that is not pinned, for one sweep that confirms they have settled. Returns whether
  // this is that sweep.
  bool next(const std::vector<unsigned char>& pinned, std::vector<Index>& todo) {
    std::sort(woken_.begin(), woken_.end());
    todo.clear();
    for (const Index c : woken_) if (!pinned[c]) todo.push_back(c);
    const bool sweep = todo.empty();
    if (sweep)
      for (Index c = 0; c < static_cast<Index>(active_.size()); ++c) if (!pinned[c]) todo.push_back(c);
    return sweep;
  }

  void clear() {
    for (const Index c : woken_) active_[c] = 0;
    woken_.clear();
  }

  // Wakes cluster c's neighbourhood (itself included).
  void wake_neighbourhood(const LevelSupport& support, Index c) {
    const int k = support.neighbors;
    const Index* nb = support.neighborhoods.data() + static_cast<std::size_t>(c) * k;
    for (int j = 0; j < k; ++j)
      if (!active_[nb[j]]) { active_[nb[j]] = 1; woken_.push_back(nb[j]); }
  }

  const std::vector<Index>& woken() const { return woken_; }

 private:
  std::vector<unsigned char> active_;
  std::vector<Index> woken_;
};

// The per-anchor state of the iteration.
struct AnchorSteps {
  std::vector<double> moves, damping, earlier;
  std::vector<unsigned char> pinned;
  explicit AnchorSteps(Index clusters)
      : moves(static_cast<std::size_t>(clusters), never), damping(static_cast<std::size_t>(clusters), 1.0),
        earlier(static_cast<std::size_t>(clusters), never), pinned(static_cast<std::size_t>(clusters), 0) {}
};

// Moves the listed anchors one damped step towards fine's foot on their normal line.
void step_anchors(const Points& fine, Points& level, Points& anchors, const LevelSupport& support,
                  const std::vector<Index>& todo, const Points& anchor_reference, AnchorSteps& steps) {
  Points query(static_cast<Eigen::Index>(todo.size()), 3), query_reference(query.rows(), 3);
  for (std::size_t j = 0; j < todo.size(); ++j) {
    query.row(j) = anchors.row(todo[j]);
    query_reference.row(j) = anchor_reference.row(todo[j]);
  }
  const Points normals = support_normals_of(query, todo, anchors, support, query_reference);
  parallel_for(todo.size(), [&](std::size_t b, std::size_t e) {
    for (std::size_t j = b; j < e; ++j) {
      const Index c = todo[j];
      const Index i = support.anchors[c];
      const Vec3 nrm = normals.row(static_cast<Eigen::Index>(j)).transpose();
      const Vec3 f = fine.row(i).transpose();
      const Vec3 p = level.row(i).transpose();
      const Vec3 target = tangent_foot(f, p, nrm);
      const double full = (target - p).norm();
      steps.damping[c] = next_damping(decompose_damping, steps.damping[c], full, steps.moves[c], 1.0);
      steps.moves[c] = full;
      level.row(i) = (p + steps.damping[c] * (target - p)).transpose();
      anchors.row(c) = level.row(i);
    }
  });
}

// After a round that did not settle: pins the anchors that stopped settling over its second
// half (all unsettled ones after a few rounds) to their finer position, so that the others
// settle around them. Anchors that still converge keep going, and from round 8 on every round
// pins at least one, so the rounds end.
void pin_unsettled(const Points& fine, Points& level, Points& anchors, const LevelSupport& support, int round,
                   double stop, AnchorSteps& steps, Consistency& out) {
  const bool last_chance = round >= 8;
  for (Index c = 0; c < support.clusters; ++c)
    if (!steps.pinned[c] && steps.moves[c] > stop && steps.moves[c] < never &&
        (last_chance || steps.moves[c] > 0.25 * steps.earlier[c])) {
      steps.pinned[c] = 1;
      ++out.pinned;
      level.row(support.anchors[c]) = fine.row(support.anchors[c]);
      anchors.row(c) = level.row(support.anchors[c]);
    }
}

// Iterates the anchors until they settle, pinning those that do not.
Consistency settle_anchors(const Points& fine, Points& level, const LevelSupport& support,
                           const Points& anchor_reference, double stop, int max_iterations,
                           const ProgressStage& stage) {
  AnchorSteps steps(support.clusters);
  WakeList wake(support.clusters);
  std::vector<Index> todo;
  Points anchors = support_centroids(level, support);  // kept equal to the anchors' rows of level
  Consistency out;
  for (int round = 0;; ++round) {
    double largest = 0.0;
    bool settled = false;
    for (int it = 0; it < max_iterations; ++it, ++out.iterations) {
      stage.report(std::min(1.0, static_cast<double>(out.iterations) / (4.0 * max_iterations)));
      if (it == max_iterations / 2) steps.earlier = steps.moves;
      const bool sweep = wake.next(steps.pinned, todo);
      step_anchors(fine, level, anchors, support, todo, anchor_reference, steps);
      largest = 0.0;
      wake.clear();
      for (const Index c : todo) {
        if (!(steps.moves[c] > stop)) continue;
        largest = std::max(largest, steps.moves[c]);
        wake.wake_neighbourhood(support, c);
      }
      if (largest <= stop && sweep) { settled = true; break; }
      // A neighbour woken by another's move starts afresh: its small old move is no measure.
      for (const Index c : wake.woken()) if (steps.moves[c] <= stop) steps.moves[c] = never;
    }
    out.residual = largest;
    if (settled) break;
    pin_unsettled(fine, level, anchors, support, round, stop, steps, out);
    std::fill(steps.moves.begin(), steps.moves.end(), never);
    wake.wake_all();
  }
  return out;
}

// Every other point in one step onto fine's normal line, and every point's detail along its
// (unoriented) normal: the move does not depend on the sign.
void offsets_along_normals(const Points& fine, Points& level, const LevelSupport& support, const LabelGroups& layout,
                           Eigen::MatrixXd::RowXpr details, Points& normals) {
  level_normals(level, support, Points(), {}, normals, &layout);
  step_non_anchors(
      fine, level, normals, support,
      [&](Eigen::Index i, const Vec3& foot, const Vec3&) { level.row(i) = foot.transpose(); },
      [&](Eigen::Index i, const Vec3&, const Vec3&) { details(i) = (fine.row(i) - level.row(i)).dot(normals.row(i)); });
}

}  // namespace

Consistency make_offsets_normal(const Points& fine, Points& level, const LevelSupport& support,
                                const LabelGroups& layout, const Points& anchor_reference, double scale,
                                int max_iterations, const ProgressStage& stage, Eigen::MatrixXd::RowXpr details,
                                Points& normals) {
  const Consistency out = settle_anchors(fine, level, support, anchor_reference, 1e-12 * scale, max_iterations, stage);
  // The iteration's temporaries go back to the system before the peak. This is the only trim
  // within a step: trims at its start and after the decimation lowered no peak, and the next
  // step's arrays faulted the same pages in again.
  release_free_memory();
  offsets_along_normals(fine, level, support, layout, details, normals);
  stage.report(1.0);
  return out;
}

}  // namespace pointscale
