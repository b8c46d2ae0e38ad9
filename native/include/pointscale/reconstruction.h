// Reconstruction (Eq. 9-11): displace P^0 level by level along normals recomputed from the
// current points of each level, so an edited base carries the detail along its new normals.
#pragma once
#include <vector>

#include "pointscale/decomposition.h"

namespace pointscale {

struct Reconstruction {
  Points positions;             // #P by 3, the finest level
  std::vector<Points> levels;   // P^0..P^k when asked for, else empty
  std::vector<Points> normals;  // n^0..n^{k-1} when asked for, else empty
};

// gains   k by 1 (per band) or k by #P (per point); band l is scaled by its gain
// base    #P by 3 edited P^0, or nullptr for the stored one (whose normals are then read from
//         the model, bit for bit what fitting them again gives)
// upto    reconstruct levels 0..upto only (upto <= k)
Reconstruction reconstruct(const MultiscaleModel& model, const Eigen::MatrixXd& gains, const Points* base,
                           bool keep_levels, int upto = -1, const ProgressCallback* progress = nullptr);

// The same from an edited base that the caller hands over (no copy of it is made).
Reconstruction reconstruct_from_base(const MultiscaleModel& model, const Eigen::MatrixXd& gains, Points base,
                                     bool keep_levels, int upto = -1, const ProgressCallback* progress = nullptr);

}  // namespace pointscale
