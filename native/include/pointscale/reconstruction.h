// Reconstruction (Eq. 9-11): displace P^0 level by level along normals recomputed from the
// current points of each level, so an edited base carries the detail along its new normals.
#pragma once
#include <vector>

#include "pointscale/decomposition.h"
#include "pointscale/spatial_order.h"

namespace pointscale {

struct Reconstruction {
  Points positions;             // #P by 3, the finest level
  std::vector<Points> levels;   // P^0..P^k when asked for, else empty
  std::vector<Points> normals;  // n^0..n^{k-1} when asked for, else empty
};

// What a caller that reconstructs over and over (Reconstructor) keeps between calls.
struct ReconstructionWorkspace {
  std::vector<LabelGroups> groups;  // per level: its points grouped like support.local, or empty
  Points normals[2];                // two levels' normals, alternating
  Points centroids;                 // a level's anchors
};

// gains     k by 1 (per band) or k by #P (per point); band l is scaled by its gain
// base      #P by 3 edited P^0, or nullptr for the stored one (whose normals are then read from
//           the model, bit for bit what fitting them again gives)
// upto      reconstruct levels 0..upto only (upto <= k)
// workspace storage kept between calls, or nullptr: arrays allocated afresh each call cost a
//           page fault per 4 KB on first touch (1300 faults, 2-3 ms, at 100k points)
Reconstruction reconstruct(const MultiscaleModel& model, const Eigen::MatrixXd& gains, const Points* base,
                           bool keep_levels, int upto = -1, const ProgressCallback* progress = nullptr,
                           ReconstructionWorkspace* workspace = nullptr);

// The same from an edited base that the caller hands over (no copy of it is made).
Reconstruction reconstruct_from_base(const MultiscaleModel& model, const Eigen::MatrixXd& gains, Points base,
                                     bool keep_levels, int upto = -1, const ProgressCallback* progress = nullptr,
                                     ReconstructionWorkspace* workspace = nullptr);

// The level loop that both of the above and Reconstructor run, on p (P^0 in, the finest level
// out). edited: p is not the stored base, so level 0's normals are fitted and oriented by the
// stored ones turned by reference_rotation (#C); kept: receives every level and its normals
// when not null; workspace: null, or what the caller keeps between calls.
void reconstruct_levels_in_place(const MultiscaleModel& model, const Eigen::MatrixXd& gains, Points& p, bool edited,
                                 const std::vector<Mat3>* reference_rotation, Reconstruction* kept, int upto,
                                 const ProgressCallback* progress, ReconstructionWorkspace* workspace);

}  // namespace pointscale
