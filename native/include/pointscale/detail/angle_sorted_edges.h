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
// points   #P by 3, or nullptr: compare n_j with n_i reflected across the plane halfway between
//          the two points, n_i - 2 (n_i . e) e for e the unit edge, instead of n_i itself. Two
//          points on one circle or sphere, normals along its radii, then agree exactly, even
//          across a part thinner than the graph's reach, where the opposite sides' normals look
//          alike to the plain weight (and give the wrong sign); across a plane they are unchanged.
// Returns every edge {i, j} with j in row i or i in row j, once, by increasing weight. The weight
// is sorted on its float's top 16 bits (a relative step of 1/128), a counting sort in two passes
// that needs no copy of the edges; within a step, edges keep the order of their first row.
// How far n_i and n_j agree across the edge between points p_i and p_j: n_i . n_j, or with
// reflect, n_j . (n_i - 2 (n_i . e) e) for e the unit edge (see points below). Its sign says
// whether they face the same way; 1 - |it| is the edge's weight.
inline double edge_agreement(const Eigen::RowVector3d& ni, const Eigen::RowVector3d& nj, const Eigen::RowVector3d& pi,
                             const Eigen::RowVector3d& pj, bool reflect) {
  double dot = ni.dot(nj);
  if (!reflect) return dot;
  const Eigen::RowVector3d d = pj - pi;
  const double d2 = d.squaredNorm();
  return d2 > 0.0 ? dot - 2.0 * ni.dot(d) * nj.dot(d) / d2 : dot;
}

std::vector<SignedEdge> angle_sorted_edges(const IndexList& rows, int width, const Points& normals,
                                           const Points* points = nullptr);

}  // namespace pointscale
