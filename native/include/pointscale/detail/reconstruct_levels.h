// The level loop of reconstruction (reconstruction.h), which reconstruct() and Reconstructor
// share, and what an edited base needs beyond the model.
#pragma once
#include <memory>
#include <vector>

#include "pointscale/reconstruction.h"
#include "pointscale/spatial_order.h"

namespace pointscale {

// What an edited reconstruction needs beyond the model (edit_rotations.h), found from the
// model alone: each base point's ring and its plane, and each point's foot. No edit changes
// it, so a Reconstructor finds it once, on its first edited call.
struct EditSupport {
  IndexList rings;        // #P by ring_size, base_rings(base, parts, edit_ring_size)
  int ring_size = 0;
  IndexList feet;         // #P, base_feet(base, base_normals, the finest level)
  EditRingPlanes planes;  // ring_planes(base, rings, ring_size)
};

// base, base_normals, finest  #P by 3: the model's base, its normals and its unedited finest
//                             level; parts: the model's part labels, or empty
EditSupport edit_support(const Points& base, const IndexList& parts, const Points& base_normals, const Points& finest);

// What every reconstruction of one model on an edited base shares, and no edit or gain
// changes: the edit support, and the stored base's level normals at unit gains (levels
// 1..k-1; level 0's are the model's), which an edited pass at those gains reads instead of
// fitting them. Read only once found, so calls on any thread can share it (EditMemo).
struct KeptEdit {
  std::shared_ptr<const EditSupport> support;
  std::shared_ptr<const std::vector<Points>> unit_normals;
};

// The unedited pass at unit gains: returns the finest level, and leaves the stored base's
// level normals at unit gains (levels 1..k-1, row 0 empty) in workspace.unedited_normals.
struct ReconstructionWorkspace;
Points unit_pass(const MultiscaleModel& model, const ProgressStage& progress, ReconstructionWorkspace& workspace);

// Those level normals alone (ReconstructionWorkspace::unit_reference).
std::shared_ptr<const std::vector<Points>> unit_level_normals(const MultiscaleModel& model,
                                                              const ProgressStage& progress);

// Whether gains (k by 1 or k by #P) are all 1.
bool all_unit(const Eigen::MatrixXd& gains);

// Finds it: a pass over the stored base's levels at unit gains (for the feet and the
// normals), then the support. Progress as two passes over the levels.
KeptEdit find_kept_edit(const MultiscaleModel& model, const ProgressStage& progress);

// An editing session's last edited call, so that the next one with the same gains does again
// only what the base's changes since then reach (reconstruction.cpp). Valid only once an
// edited call completes; its arrays keep their storage from call to call. 49 bytes a point.
struct LastEdit {
  bool valid = false;
  Points base;                       // #P by 3, the edited base it was given
  Points result;                     // #P by 3, its finest level
  Eigen::MatrixXd gains;             // its gains
  std::vector<Mat3> clusters;        // #C level 0's cluster turns (transported_rotations)
  std::vector<unsigned char> kinds;  // #P how each ring's turn was measured (edit_rotations)
};

// The working storage of the level loop. reconstruct() makes a fresh one per call; a
// Reconstructor keeps one between calls.
struct ReconstructionWorkspace {
  std::vector<LabelGroups> groups;  // per level: its points grouped like support.local, or empty
  Points normals[2];                // two levels' normals, alternating
  Points centroids;                 // a level's anchors
  std::shared_ptr<const EditSupport> edit;  // found on the first edited call, or shared (KeptEdit)
  std::vector<Mat3> rotation;       // an edited base: each point's turn
  Points unedited;                  // an edited base: the level as the stored base gives it
  // An edited base: the stored base's level normals for the gains last used, 1..levels - 1
  // (level 0's are the model's). They do not depend on the edit, so an editing session that
  // keeps its gains fits them once.
  Eigen::MatrixXd unedited_gains;
  std::vector<Points> unedited_normals;
  // Or, at unit gains, those normals found once for the model and shared (KeptEdit): read only.
  std::shared_ptr<const std::vector<Points>> unit_normals;
  // At other gains, the stored base's level normals at unit gains (levels 1..levels - 1, as
  // unit_level_normals gives them): each level's normals take the side of the sum of these and
  // the level's below (reference). Where detail stands on a wall, a level's normals are at
  // right angles to the level's below, and the side taken from those alone was a toss-up that
  // a gain of 1.001 turned over (band offsets then flipped, and points jumped 1-4% of the
  // model). Null at unit gains, which need none: the normals are these.
  std::shared_ptr<const std::vector<Points>> unit_reference;
  Points reference;
  // An edited base: each point's detail before the edit's turn, the sum over the levels of
  // gain x detail x the stored base's level normal. Every level's normal at a point turns by
  // the turn at its foot, so the edited finest level is the edited base plus that turn of it
  // (then hung from the foot). It depends on the gains alone (detail_gains: empty until it is
  // complete), so an editing session that keeps its gains sums it once: 24 bytes a point.
  Points detail;
  Eigen::MatrixXd detail_gains;
  bool kept = false;  // kept between calls: the unedited normals are worth keeping
  LastEdit last;      // kept between calls: the last edited call
};

// The level loop that reconstruct(), reconstruct_from_base() and Reconstructor run, on p (P^0 in, the finest level
// out). edited: p may differ from the stored base, so the levels of the stored base are built
// beside it, and each level's normals, fitted there, are turned by the edit's rotation at each
// point; kept: receives every level and its normals when not null; workspace: the storage,
// which must hold the edit support when edited (its feet sized #P); progress: reported at
// least once per level, so a callback can cancel (and is checked) even where every level's
// normals are cached; keep_normals: an unedited pass leaves its level normals in the
// workspace's unedited_normals, with its gains, for an edited pass after it at those gains
// (an edited base needs an unedited pass first, for the feet). Returns how the edit's turns
// were measured.
EditRotationReport reconstruct_levels_in_place(const MultiscaleModel& model, const Eigen::MatrixXd& gains, Points& p,
                                               bool edited, Reconstruction* kept, int upto,
                                               const ProgressStage& progress, ReconstructionWorkspace& workspace,
                                               bool keep_normals = false);

}  // namespace pointscale
