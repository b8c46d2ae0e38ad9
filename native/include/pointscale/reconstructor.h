// Reconstruction from one model over and over, as an editing session runs it (Sec. 8.1): a
// solver beside the free functions of reconstruction.h. It holds the model in a spatially
// coherent point order (level 0's clusters one after another), each level's grouping by
// cluster and the working storage, so that a call costs the fits and little else. Its results
// are bit for bit those of reconstruct(). It copies the model (about its size again).
#pragma once
#include <mutex>

#include "pointscale/reconstruction.h"

namespace pointscale {

class Reconstructor {
 public:
  explicit Reconstructor(const MultiscaleModel& model);

  // gains   k by 1 (per band) or k by #P (per point, in the model's point order)
  // base    #P by 3 row-major (a NumPy array's buffer), an edited P^0 in the caller's
  //         coordinates, or nullptr for the stored base
  // origin  the caller's coordinates minus the model's: subtracted from base, added to the result
  // Returns the finest level, #P by 3. One call at a time: a call waits for the one before.
  Points reconstruct(const Eigen::MatrixXd& gains, const double* base, const Vec3& origin,
                     const ProgressCallback* progress = nullptr);

  Eigen::Index points() const { return model_.base.rows(); }
  int bands() const { return model_.bands(); }

 private:
  MultiscaleModel model_;  // reordered: row r (column r of details) is point order_[r]
  IndexList order_;        // #P
  ReconstructionWorkspace workspace_;
  Points level_;           // the level being built, reordered
  Eigen::MatrixXd gains_;  // per-point gains, reordered
  std::mutex busy_;
};

}  // namespace pointscale
