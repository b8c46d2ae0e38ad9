// decompose's step that makes each level's offsets normal (Sec. 7): after the projection
// P^{l-1} = Psi(P^l), each p^{l-1} moves within its tangent plane until p^l - p^{l-1} lies
// exactly along n^{l-1}(P^{l-1}), the normal that reconstruction recomputes from the level.
#pragma once
#include "pointscale/detail/cluster_layout.h"
#include "pointscale/detail/level_normals.h"

namespace pointscale {

struct Consistency {
  int iterations = 0;
  double residual = 0.0;    // largest anchor move left before pinning, in coordinates
  std::size_t pinned = 0;   // anchors kept at their finer position
};

// The level aligner (align_level.h) with decompose's policy: normals depend on the anchors only
// (level_support.h), so the anchors are iterated first, each halving its step when its move
// grows (near sharp features the plain iteration swings with slope about -d kappa). An anchor
// that still does not settle is pinned to its finer position (no detail in this band; the
// coarser bands carry it). Then every other point is made consistent in one step, since its
// normal no longer depends on it: exact by construction.
// fine              #P by 3, P^l
// level             #P by 3, P^{l-1} as projected; moved in place
// layout            the points grouped as support.local is laid out (cluster_layout.h)
// anchor_reference  #C by 3, orients the anchors' normals during the iteration
// scale             the input's extent: an anchor has settled once it moves under 1e-12 of it
// details           receives each point's detail along its unoriented normal (#P)
// normals           receives those normals (#P by 3, the eigenvector's own sign): decompose
//                   orients them, and flips the details with them, once level 0 is known
Consistency make_offsets_normal(const Points& fine, Points& level, const LevelSupport& support,
                                const LabelGroups& layout, const Points& anchor_reference, double scale,
                                int max_iterations, const ProgressStage& stage, Eigen::MatrixXd::RowXpr details,
                                Points& normals);

}  // namespace pointscale
