// Reconstruction (Eq. 9-11): displace P^0 level by level along each level's normals. The
// normals of a level are fitted to its current points (so band gains bend the finer detail
// with the coarser), on the stored base; an edited base turns them, point by point, as the
// edit turns the base around that point (edit_rotations.h), so the detail follows an edit of
// any scale upright.
#pragma once
#include <vector>

#include "pointscale/decomposition.h"
#include "pointscale/edit_rotations.h"

namespace pointscale {

struct Reconstruction {
  Points positions;             // #P by 3, the finest level
  std::vector<Points> levels;   // P^0..P^k when asked for, else empty
  std::vector<Points> normals;  // n^0..n^{k-1} when asked for, else empty
  EditRotationReport edit;      // how the edit's turns were measured (all zero when unedited)
};

// gains     k by 1 (per band) or k by #P (per point); band l is scaled by its gain
// base      #P by 3 edited P^0, or nullptr for the stored one (whose normals are then read from
//           the model, bit for bit what fitting them again gives)
// upto      reconstruct levels 0..upto only (upto <= k)
// Stateless: every call finds what an edited base needs afresh (the rings, planes and feet of
// edit_rotations.h) and allocates its own arrays. A caller that reconstructs one model over
// and over keeps a Reconstructor (reconstructor.h), the one cache of those.
Reconstruction reconstruct(const MultiscaleModel& model, const Eigen::MatrixXd& gains, const Points* base,
                           bool keep_levels, int upto = -1, const ProgressCallback* progress = nullptr);

// The same from an edited base that the caller hands over (no copy of it is made).
Reconstruction reconstruct_from_base(const MultiscaleModel& model, const Eigen::MatrixXd& gains, Points base,
                                     bool keep_levels, int upto = -1, const ProgressCallback* progress = nullptr);

// The level loop behind both, shared with Reconstructor: detail/reconstruct_levels.h.

}  // namespace pointscale
