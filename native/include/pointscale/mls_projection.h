// The MLS projection operator Psi (Sec. 2), almost-orthogonal variant: fit the weighted plane at
// the current foot point, project the ORIGINAL point onto it, repeat. At the fixed point the
// offset is exactly along the fitted normal, so a scalar detail coefficient loses nothing.
#pragma once
#include "pointscale/progress.h"
#include "pointscale/spatial_index.h"
#include "pointscale/types.h"

namespace pointscale {

struct MlsOptions {
  int neighbors = 24;         // support points in each plane fit
  double tolerance = 1e-7;    // convergence: the foot point within tolerance x h of its limit, by its
                              // step, or by step x r / (1 - r) while steps shrink at a rate r < 0.5
  int max_iterations = 30;    // iteration cap per point
  // Thin sheets: given the support points' normals (#S by 3, sign ignored), a support point's
  // weight also falls with the distance of the projected point x from it along its own normal,
  // as exp(-(n_j.(p_j - x))^2 / (sheet h_j)^2), so two sheets closer than h (but more than about
  // 2 sheet h apart) are not averaged into one. nullptr keeps isotropic weights.
  const Points* support_normals = nullptr;
  double sheet = 0.2;         // normal kernel width as a fraction of h, in (0, 1]
  bool thin_sheets = false;   // the same weights with normals estimated from 16 support neighbours
  // The order in which the points are projected (spatial_order.h; #X), or nullptr to compute a
  // Morton order; callers projecting the same points repeatedly compute it once.
  const IndexList* order = nullptr;
  // A support point near each point (#X, e.g. its decimation cluster's centroid), with the
  // points ordered by it: a point's first query is then centred there, asking for more
  // candidates, so that one query serves all the points around that support point.
  const IndexList* near_support = nullptr;
};
// (decompose also hands the projection its thin sheets' sides and its support's rows:
// detail/mls_hints.h.)

// Candidates beyond the k a fit takes that a query centred on a support point asks for.
constexpr int near_query_extra = 16;

struct MlsResult {
  Points positions;           // #X by 3 projected points
  Points normals;             // #X by 3 unit normals of the surface there (sign arbitrary)
  std::size_t not_converged = 0;  // points that hit the iteration cap
  std::size_t degenerate = 0;     // points whose neighbourhood defines no plane (left in place)
};

// x        #X by 3 points to project
// support  spatial index on the #S support points that define the surface
// h        #S kernel widths, one per support point (weights exp(-r^2/h_j^2))
// Throws std::invalid_argument for options out of range (validate, validation.h), points that
// are not finite, or options.order, options.near_support or options.support_normals of
// another size than #X (#S for the normals).
MlsResult mls_project(const Points& x, const SpatialIndex& support, const Eigen::VectorXd& h,
                      const MlsOptions& options, const ProgressStage& stage = {});

}  // namespace pointscale
