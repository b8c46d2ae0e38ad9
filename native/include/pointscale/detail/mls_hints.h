// What decompose hands the MLS projection beyond MlsOptions (mls_projection.h): inputs and
// shared work that only it has, kept out of the public options.
#pragma once
#include "pointscale/mls_projection.h"
#include "pointscale/detail/support_neighbours.h"

namespace pointscale {

struct MlsHints {
  // Sides (decompose's thin sheets, thin_sheets.h): oriented normals of the points (#X by 3)
  // and of the support points (#S by 3). A point's fit then takes only the support points that
  // face its own way (same_side in thin_sheets.h), so the far side of a wall of any thickness
  // never weighs in, while the near side is smoothed as it would be alone. Both or neither.
  const Points* point_sides = nullptr;
  const Points* support_sides = nullptr;
  // With options.near_support, the support's rows from support_neighbours(support, neighbors +
  // near_query_extra), made by the caller for its kernel widths too: they stand in for the
  // queries centred on support points (the same candidates in the same order). Used when their
  // width is the projection's query width (not with sides, which ask for more).
  const SupportNeighbours* near_rows = nullptr;
};

MlsResult mls_project(const Points& x, const SpatialIndex& support, const Eigen::VectorXd& h,
                      const MlsOptions& options, const MlsHints& hints, const ProgressStage& stage = {});

}  // namespace pointscale
