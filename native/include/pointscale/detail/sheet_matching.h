// One model's offsets over a common base carried onto another's samples (morph.h), sheet by
// sheet where both fold over the base.
#pragma once
#include "pointscale/progress.h"
#include "pointscale/types.h"

namespace pointscale {

// B's offsets on A's samples. Where B folds over the base (a bunny's ears over an ellipsoid),
// the nearest feet of B around an A foot come from two or more sheets of B, and a mean over
// them lands between the sheets. Where A folds there as well, into as many sheets, each A
// sample takes B's sheet of the same rank along the normal (inner to inner, outer to outer);
// into another number of sheets, the sheet of the B neighbour whose offset is nearest its own.
// Where A does not fold (or B does not), the Gaussian-weighted mean over every neighbour, as
// knn_interpolate, bit for bit: a face's nose that folds in B only stays whole.
//
// from       #B by 3 B's feet on the base
// values     #B B's offsets along the base normal
// to         #A by 3 A's feet on the base
// to_values  #A A's offsets
// k          neighbours of B per A sample (and of A, for A's own sheets), at least 1
// stage      progress, and cancellation
// Returns #A offsets.
Eigen::VectorXd offsets_on_matching_sheets(const Points& from, const Eigen::VectorXd& values, const Points& to,
                                           const Eigen::VectorXd& to_values, int k, const ProgressStage& stage);

}  // namespace pointscale
