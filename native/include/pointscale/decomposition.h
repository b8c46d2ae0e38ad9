// The integrated smoothing and decomposition operator (Sec. 7): decimate, project onto the MLS
// surface of the decimated level, take signed normal offsets (Eq. 8, 17), repeat.
#pragma once
#include <vector>

#include "pointscale/diffusion.h"
#include "pointscale/level_support.h"
#include "pointscale/mls_projection.h"
#include "pointscale/progress.h"

namespace pointscale {

struct DecomposeOptions {
  int levels = 4;             // point clouds P^0..P^k, so levels - 1 detail bands
  double decimation = 0.25;   // gamma: |Q^{l-1}| = gamma^(k-l+1) n
  double kernel = 1.0;        // h = kernel x local spacing of the decimated level
  double max_variation = 0.05;  // decimation: split curved clusters first above this
  MlsOptions mls;             // projection neighbours, tolerance, iteration cap
  int consistency_iterations = 60;  // cap per round for making offsets exactly normal
  const DiffusionOptions* diffusion = nullptr;  // smoother "diffusion" (Sec. 5.1): diffuse each Q^{l-1} first
  // Keep two-sided thin sheets apart (thin_sheets.h), telling the sides by the input normals,
  // which must then be given; the projection's normal kernel is mls.sheet x h wide.
  bool thin_sheets = false;
};

// What happened at one level, for the user.
struct LevelReport {
  std::size_t support_points = 0;      // |Q^l|
  double kernel_width = 0.0;           // median h at this level
  std::size_t not_converged = 0;       // projections that hit the iteration cap
  std::size_t degenerate = 0;          // points with no plane in their neighbourhood
  int consistency_iterations = 0;
  double consistency_residual = 0.0;   // largest anchor move left before pinning, in coordinates
  std::size_t pinned = 0;              // anchors kept at their finer position (no detail here)
};

// A multiscale representation P^0 + D^0 + ... + D^{k-1} (Eq. 11), in the caller's coordinates.
struct MultiscaleModel {
  Points base;                       // #P by 3, P^0
  Eigen::MatrixXd details;           // k by #P, D^l, signed along the oriented normals
  Points base_normals;               // #P by 3, oriented normals of P^0 (orientation reference)
  std::vector<LevelSupport> support; // k, the cached neighbourhoods of levels 0..k-1
  std::vector<LevelReport> reports;  // k, level 0 first
  // #P the connected part of each point (connected_parts.h), or empty for one part. Parts are
  // decomposed apart (pointscale.parts), and the rings an edit is measured on stay within them.
  IndexList parts;
  int bands() const { return static_cast<int>(details.rows()); }
};

// points         #P by 3 (the caller centres them; precision is relative to their extent)
// input_normals  #P by 3 or nullptr: orient level 0 like these, else by spanning-tree propagation
// progress       may be null; returning false throws Cancelled and nothing is produced
//
// Each level's points are made consistent with the normals that reconstruction will recompute
// from them: after the projection P^{l-1} = Psi(P^l), each p^{l-1} is moved within its tangent
// plane until p^l - p^{l-1} lies exactly along n^{l-1}(P^{l-1}). The move is tiny (the
// projection is already almost orthogonal) and makes unedited reconstruction exact.
// points is taken by value: it becomes the finest level, so a caller that moves it in saves a copy.
// Throws std::invalid_argument for input that check_decompose_input (validation.h) refuses.
MultiscaleModel decompose(Points points, const Points* input_normals, const DecomposeOptions& options,
                          const ProgressCallback* progress = nullptr);

// The same with the normals handed over: with thin sheets they are released once the points'
// own numbering holds them (at the first decimation), so that a decomposition of a large
// two-sided scan does not hold them twice.
MultiscaleModel decompose(Points points, Points input_normals, const DecomposeOptions& options,
                          const ProgressCallback* progress = nullptr);

}  // namespace pointscale
