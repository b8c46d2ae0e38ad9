// One MLS pass, as PCL's and Open3D's MLS smoothing do it: each point moves once onto the
// weighted plane (Eq. 2-3) of its k nearest support points, fitted at the point itself. The
// iteration of mls_projection.h would go on from there to the fixed point of Psi; this stops
// after its first step, so it needs none of the convergence machinery and one neighbour query
// per point. How far from the fixed point it stops is told, when asked, by the step the
// iteration would take next (its second fit, at the foot, on the foot's own neighbours).
#pragma once
#include "pointscale/progress.h"
#include "pointscale/spatial_index.h"
#include "pointscale/types.h"

namespace pointscale {

struct SinglePassResult {
  Points positions;            // #X by 3 projected points
  Points normals;              // #X by 3 unit normals of the fitted planes (sign arbitrary)
  Eigen::VectorXd moved;       // #X |foot - x| / h: the pass's own step
  Eigen::VectorXd next_step;   // #X the iteration's second step / h there, or empty unless asked
                               // for (a second query and fit per point)
  std::size_t degenerate = 0;  // points whose neighbourhood defines no plane (left in place, 0 steps)
};

// x        #X by 3 points to project
// self     x holds exactly the support's points, row for row: the neighbour rows then come
//          from one self_knn pass (self_knn.h), which also gives the kernel widths
// support  spatial index on the #S support points
// kernel   kernel width as a multiple of the local spacing (local_spacing(support, 6))
// k        support points in each plane fit
// estimate  fill next_step too (what the report asks for)
// Throws std::invalid_argument for a kernel, k or points that validation.h refuses.
// Each step is relative to h of the support point nearest to where its fit is made, as the
// iteration's tolerance measures it.
SinglePassResult mls_single_pass(const Points& x, bool self, const SpatialIndex& support, double kernel, int k,
                                 bool estimate, const ProgressStage& stage = {});

}  // namespace pointscale
