// Reconstruction (Eq. 9-11): displace P^0 level by level along each level's normals. The
// normals of a level are fitted to its current points (so band gains bend the finer detail
// with the coarser), on the stored base; an edited base turns them, point by point, as the
// edit turns the base around that point (edit_rotations.h), so the detail follows an edit of
// any scale upright.
#pragma once
#include <memory>
#include <mutex>
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

struct KeptEdit;  // detail/reconstruct_levels.h

// What one model's stateless reconstructions on an edited base share: the first such call
// given it finds what every edit needs (each base point's ring, plane and foot, and the stored
// base's level normals at unit gains) and leaves it here; the calls after it read it, so they
// cost the edited pass alone. Nothing in it depends on an edit or on gains, and once found it
// is read only: calls on any thread may share one. It holds about 250 bytes a point (4
// levels). A memo belongs to one model: handed to a model of another size it is an error
// (std::invalid_argument); one of the same size cannot be told apart.
class EditMemo {
 public:
  std::shared_ptr<const KeptEdit> get() const;
  void keep(std::shared_ptr<const KeptEdit> found);
  // The stored base's level normals at unit gains, which orient the calls at other gains, kept
  // by the first of them that is not edited (an edited one finds them with the KeptEdit).
  std::shared_ptr<const std::vector<Points>> unit_reference() const;
  void keep_unit_reference(std::shared_ptr<const std::vector<Points>> found);

 private:
  mutable std::mutex mutex_;
  std::shared_ptr<const KeptEdit> kept_;
  std::shared_ptr<const std::vector<Points>> unit_reference_;
};

// gains     k by 1 (per band) or k by #P (per point); band l is scaled by its gain
// base      #P by 3 edited P^0, or nullptr for the stored one (whose normals are then read from
//           the model, bit for bit what fitting them again gives)
// upto      reconstruct levels 0..upto only (upto <= k)
// memo      the model's EditMemo, or nullptr: every call on an edited base then finds what the
//           edit needs afresh (the rings, planes and feet of edit_rotations.h), and every call
//           at gains other than 1 the level normals at unit gains, which orient its own
// Each call allocates its own working arrays. A caller that reconstructs one model over and
// over keeps a Reconstructor (reconstructor.h), which also keeps those and lays the model out
// in a spatial order. Results are bit for bit the same with a memo or without.
Reconstruction reconstruct(const MultiscaleModel& model, const Eigen::MatrixXd& gains, const Points* base,
                           bool keep_levels, int upto = -1, const ProgressCallback* progress = nullptr,
                           EditMemo* memo = nullptr);

// The same from an edited base that the caller hands over (no copy of it is made).
Reconstruction reconstruct_from_base(const MultiscaleModel& model, const Eigen::MatrixXd& gains, Points base,
                                     bool keep_levels, int upto = -1, const ProgressCallback* progress = nullptr,
                                     EditMemo* memo = nullptr);

// The level loop behind both, shared with Reconstructor: detail/reconstruct_levels.h.

}  // namespace pointscale
