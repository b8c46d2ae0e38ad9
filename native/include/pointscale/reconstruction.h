// Reconstruction (Eq. 9-11): displace P^0 level by level along each level's normals. The
// normals of a level are fitted to its current points (so band gains bend the finer detail
// with the coarser), on the stored base; an edited base turns them, point by point, as the
// edit turns the base around that point (edit_rotations.h), so the detail follows an edit of
// any scale upright.
#pragma once
#include <vector>

#include "pointscale/decomposition.h"
#include "pointscale/edit_rotations.h"
#include "pointscale/spatial_order.h"

namespace pointscale {

struct Reconstruction {
  Points positions;             // #P by 3, the finest level
  std::vector<Points> levels;   // P^0..P^k when asked for, else empty
  std::vector<Points> normals;  // n^0..n^{k-1} when asked for, else empty
  EditRotationReport edit;      // how the edit's turns were measured (all zero when unedited)
};

// What an edited base needs: found once per model, since no edit changes it.
struct EditSupport {
  IndexList rings;       // #P by ring_size, base_rings(base, parts)
  int ring_size = 0;
  IndexList feet;        // #P, base_feet(base, base_normals, the finest level)
  EditRingPlanes planes; // ring_planes(base, rings, ring_size)
};

// What a caller that reconstructs over and over (Reconstructor) keeps between calls.
struct ReconstructionWorkspace {
  std::vector<LabelGroups> groups;  // per level: its points grouped like support.local, or empty
  Points normals[2];                // two levels' normals, alternating
  Points centroids;                 // a level's anchors
  EditSupport edit;                 // found on the first edited call
  std::vector<Mat3> rotation;       // an edited base: each point's turn
  Points unedited;                  // an edited base: the level as the stored base gives it
  // An edited base: the stored base's level normals for the gains last used, 1..levels - 1
  // (level 0's are the model's). They do not depend on the edit, so an editing session that
  // keeps its gains fits them once.
  Eigen::MatrixXd unedited_gains;
  std::vector<Points> unedited_normals;
};

// gains     k by 1 (per band) or k by #P (per point); band l is scaled by its gain
// base      #P by 3 edited P^0, or nullptr for the stored one (whose normals are then read from
//           the model, bit for bit what fitting them again gives)
// upto      reconstruct levels 0..upto only (upto <= k)
// workspace storage kept between calls, or nullptr (arrays allocated afresh each call fault
//           their pages in again on first touch)
Reconstruction reconstruct(const MultiscaleModel& model, const Eigen::MatrixXd& gains, const Points* base,
                           bool keep_levels, int upto = -1, const ProgressCallback* progress = nullptr,
                           ReconstructionWorkspace* workspace = nullptr);

// The same from an edited base that the caller hands over (no copy of it is made).
Reconstruction reconstruct_from_base(const MultiscaleModel& model, const Eigen::MatrixXd& gains, Points base,
                                     bool keep_levels, int upto = -1, const ProgressCallback* progress = nullptr,
                                     ReconstructionWorkspace* workspace = nullptr);

// The level loop behind both, shared with Reconstructor: detail/reconstruct_levels.h.

}  // namespace pointscale
