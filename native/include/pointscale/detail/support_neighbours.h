// A decimated level's support points, each asked once for its nearest support points. The rows
// serve two passes of a decomposition step that each made a kd-tree query per support point:
// the kernel widths (local spacing) and the MLS queries centred on support points.
#pragma once
#include "pointscale/spatial_index.h"
#include "pointscale/types.h"

namespace pointscale {

struct SupportNeighbours {
  int width = 0;               // entries per row: min(requested width, #S)
  IndexList nearest;           // #S by width: each support point's nearest, closest first
  Eigen::VectorXd reach;       // #S distance to the row's last entry; +inf when a row holds all
};

// index    the #S support points
// width    entries per row
// spacing  if not null, receives #S local_spacing(index, spacing_k): the same values, from
//          the same queries, when width >= spacing_k + 8 (the first spacing_k + 8 entries of
//          a row are what it asks for)
SupportNeighbours support_neighbours(const SpatialIndex& index, int width, int spacing_k = 6,
                                     Eigen::VectorXd* spacing = nullptr);

}  // namespace pointscale
