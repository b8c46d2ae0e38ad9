// The one offset aligner, serving decompose (make_offsets_normal) and encode_onto: it makes
// fine - level lie along the level's recomputed normals (Sec. 7, Sec. 8.2). The anchors, on
// whose positions alone the normals depend, move by damped steps towards the foot of their fine
// point in their tangent plane; then every other point moves there in one step, exact by
// construction since its normal does not depend on it.
// The two callers solve the same condition in different settings, so an AlignPolicy states
// where they differ: how a step is damped, which anchors each iteration visits, what happens to
// an anchor that does not settle, and whether a point may leave the base's surface. Each
// caller's arithmetic is exactly what it was with its own loop, and so are its results.
#pragma once
#include <cstddef>

#include "pointscale/level_support.h"
#include "pointscale/progress.h"
#include "pointscale/spatial_index.h"

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

struct AlignPolicy {
  DampingPolicy damping;
  // Each anchor's damping starts at its Newton step 1 / (1 + |detail| x curvature) and regains
  // no more than that; else it starts at 1 and regains up to 1.
  bool newton_start = false;
  // Each iteration visits only the anchors that moved or whose neighbours moved (a real scan
  // takes hundreds of iterations over a few anchors each), then all of them once to confirm;
  // else every anchor that is free to move, every iteration.
  bool wake_list = false;
  // An anchor that does not settle within a round is pinned to its fine position (no detail in
  // this band; the coarser bands carry it) and the others go another round; else the alignment
  // ends after one round, settled or not.
  bool pin_unsettled = false;
  // A point whose consistent position lies farther than its reach (its cluster's kernel width,
  // or a twentieth of its offset) from where it started stays there: beyond a base's centres of
  // curvature the condition has no stable solution, and moving such points would drag the level
  // off the base.
  bool keep_out_of_reach = false;
  // When set, a slide longer than 1e-3 of the cluster's kernel width is followed by a step along
  // the point's normal back onto this MLS surface (kernel widths surface_h), which keeps
  // fine - level along the normal, so the level stays on the surface.
  const SpatialIndex* surface = nullptr;
  const Eigen::VectorXd* surface_h = nullptr;
  int surface_neighbors = 24;
  // Whether the iteration that found every anchor settled counts in the iterations reported
  // (encode counts it, decompose does not; each keeps the figure it has always reported).
  bool count_settling_iteration = false;
};

// decompose's: halve the step while the move grows, down to 1/64, regain it by half again
// otherwise; wake list; pin what does not settle.
inline AlignPolicy decompose_alignment() {
  AlignPolicy p;
  p.damping = DampingPolicy{1.0, 1.0 / 64.0, 1.5, true};
  p.wake_list = true;
  p.pin_unsettled = true;
  return p;
}

// encode_onto's: a move more than a tenth above the last halves the step, down to 1/1024; a
// smaller move lets it grow back by a quarter, up to the Newton step, so that noise in the
// neighbours' moves cannot stall an anchor. Every anchor every iteration; points out of reach
// stay; slides step back onto the base's surface.
inline AlignPolicy encode_alignment(const SpatialIndex& surface, const Eigen::VectorXd& surface_h, int neighbors) {
  AlignPolicy p;
  p.damping = DampingPolicy{1.1, 1.0 / 1024.0, 1.25, false};
  p.newton_start = true;
  p.keep_out_of_reach = true;
  p.surface = &surface;
  p.surface_h = &surface_h;
  p.surface_neighbors = neighbors;
  p.count_settling_iteration = true;
  return p;
}

struct AnchorAlignment {
  int iterations = 0;
  double residual = 0.0;   // largest anchor move left in the last round (0 once settled)
  std::size_t frozen = 0;  // anchors pinned (decompose) or kept out of reach (encode)
};

// Aligns one level in two steps, anchors first (align_anchors), then, from the level's normals
// fitted once the anchors have settled, every other point (align_others).
// fine   #P by 3, the finer positions P^l
// level  #P by 3, P^{l-1}; moved in place
class LevelAligner {
 public:
  LevelAligner(const Points& fine, Points& level, const LevelSupport& support, const AlignPolicy& policy);

  // anchor_reference  #C by 3, orients the anchors' normals during the iteration
  // stop              an anchor has settled once it moves no more than this
  AnchorAlignment align_anchors(const Points& anchor_reference, double stop, int max_iterations,
                                const ProgressStage& stage);

  // normals  #P by 3, the level's, fitted after align_anchors. Returns the points (not
  // anchors) kept out of reach.
  std::size_t align_others(const Points& normals);

 private:
  const Points& fine_;
  Points& level_;
  const LevelSupport& support_;
  AlignPolicy policy_;
  Points start_;  // the level as it came, for the reach rule (empty without it)
};

}  // namespace pointscale
