// Reconstruction from one model over and over, as an editing session runs it (Sec. 8.1): a
// solver beside the free functions of reconstruction.h (which keep only an EditMemo between
// calls). It holds the model in a spatially coherent point
// order (level 0's clusters one after another), each level's grouping by cluster, the working
// storage, and, from its first edited call on, what an edited base needs (the rings, planes
// and feet of edit_rotations.h), the stored base's level normals for the gains last used and
// each point's detail summed over them (ReconstructionWorkspace::detail), and its last edited
// call. So an edited call costs the edit's turns and little else, and one that changed a few
// points since the last redoes only what they reach. Its results are bit for bit those of
// reconstruct(). It copies the model (about its size again).
#pragma once
#include <memory>
#include <mutex>

#include "pointscale/reconstruction.h"

namespace pointscale {

class Reconstructor {
 public:
  explicit Reconstructor(const MultiscaleModel& model);
  ~Reconstructor();
  Reconstructor(const Reconstructor&) = delete;
  Reconstructor& operator=(const Reconstructor&) = delete;

  // gains   k by 1 (per band) or k by #P (per point, in the model's point order)
  // base    #P by 3 row-major (a NumPy array's buffer), an edited P^0 in the caller's
  //         coordinates, or nullptr for the stored base
  // origin  the caller's coordinates minus the model's: subtracted from base, added to the result
  // Returns the finest level, #P by 3. One call at a time: a call waits for the one before.
  Points reconstruct(const Eigen::MatrixXd& gains, const double* base, const Vec3& origin,
                     const ProgressCallback* progress = nullptr);

  Eigen::Index points() const;
  int bands() const;

 private:
  struct State;  // the reordered model and the workspace (detail/reconstruct_levels.h)
  std::unique_ptr<State> state_;
  std::mutex busy_;
};

}  // namespace pointscale
