// The edges of a k-nearest-neighbour graph sorted for Kruskal's minimum spanning tree under the
// weight 1 - |n_i . n_j| (Hoppe et al. 1992): the order in which a spanning tree of the
// normals' best agreements takes them.
#pragma once
#include <cstdint>
#include <vector>

#include "pointscale/types.h"

namespace pointscale {

// One undirected edge {a, b}. The top bit of b_flip says whether the two normals point to
// opposite sides (n_a . n_b < 0); the other 31 bits are b (Index is 31 bits).
struct SignedEdge {
  std::uint32_t a;
  std::uint32_t b_flip;
};

// rows     #P by width row-major: point i's nearest points (itself may be among them)
// normals  #P by 3 unit normals, sign arbitrary (zero rows allowed: their edges weigh 1)
// Returns every edge {i, j} with j in row i or i in row j, once, by increasing weight. The weight
// is sorted on its float's top 16 bits (a relative step of 1/128), a counting sort in two passes
// that needs no copy of the edges; within a step, edges keep the order of their first row.
std::vector<SignedEdge> angle_sorted_edges(const IndexList& rows, int width, const Points& normals);

}  // namespace pointscale
