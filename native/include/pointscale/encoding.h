// Encoding a model onto a user-given base surface (Sec. 8.2, Fig. 8): one detail band over a base
// that is not a low-pass version of the model, such as an ellipsoid.
#pragma once
#include "pointscale/decomposition.h"

namespace pointscale {

struct EncodeOptions {
  double kernel = 1.0;         // h = kernel x local spacing of the base samples
  MlsOptions mls;              // projection onto the base
  double max_variation = 0.05; // clustering of the projected points into the level's support
  int consistency_iterations = 200;  // cap for making offsets exactly normal
};

// points  #P by 3 model samples (the caller centres them)
// base    #B by 3 samples of the base surface; the model may lie far outside its kernels: the
//         weights are scaled before exponentiation and neighbourhoods are k-nearest, never empty
// base_normals  #B by 3 or nullptr: orients the base (else outward by propagation)
// Returns a one-band MultiscaleModel: P^0 on the base's MLS surface, D^0 the normal offsets,
// made consistent with the normals that reconstruction recomputes. reports[0].pinned counts the
// points left inconsistent (see detail/align_level.h), consistency_residual their largest error.
// Throws std::invalid_argument for options, points, base or base_normals that validation.h
// refuses (messages call the base base_points, as the package does).
MultiscaleModel encode_onto(const Points& points, const Points& base, const Points* base_normals,
                            const EncodeOptions& options, const ProgressCallback* progress = nullptr);

}  // namespace pointscale
