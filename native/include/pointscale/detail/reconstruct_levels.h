// The level loop of reconstruction (reconstruction.h), which reconstruct() and Reconstructor
// share, and what an edited base needs beyond the model.
#pragma once
#include "pointscale/reconstruction.h"

namespace pointscale {

// What an edited reconstruction needs beyond the model (edit_rotations.h), found from the
// model alone: each base point's ring and its plane, and each point's foot (from the model's
// own unedited reconstruction). Kept in the workspace, since it is costly to find.
EditSupport edit_support(const MultiscaleModel& model);

// The level loop that reconstruct(), reconstruct_from_base() and Reconstructor run, on p (P^0 in, the finest level
// out). edited: p may differ from the stored base, so the levels of the stored base are built
// beside it, and each level's normals, fitted there, are turned by the edit's rotation at each
// point; kept: receives every level and its normals when not null; workspace: null, or what
// the caller keeps between calls. Returns how the edit's turns were measured.
EditRotationReport reconstruct_levels_in_place(const MultiscaleModel& model, const Eigen::MatrixXd& gains, Points& p,
                                               bool edited, Reconstruction* kept, int upto,
                                               const ProgressCallback* progress, ReconstructionWorkspace* workspace);

}  // namespace pointscale
