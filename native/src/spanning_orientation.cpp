#include "pointscale/detail/spanning_orientation.h"

#include <utility>
#include <vector>

#include "pointscale/detail/angle_sorted_edges.h"
#include "pointscale/parallel.h"
#include "pointscale/detail/signed_union_find.h"

namespace pointscale {

void orient_along_spanning_tree(const Points& points, Points& normals, IndexList&& rows, int width, bool reflect) {
  const std::size_t n = static_cast<std::size_t>(points.rows());
  if (n == 0) return;
  std::vector<SignedEdge> edges;
  {
    const IndexList graph = std::move(rows);
    edges = angle_sorted_edges(graph, width, normals, reflect ? &points : nullptr);
  }
  // Kruskal: an edge joins two pieces of the forest only if no lighter path joins them, and
  // then it fixes their relative sign. One thread: each join depends on all lighter ones.
  SignedUnionFind forest(n);
  std::size_t joins = 0;
  for (const SignedEdge& e : edges) {
    if (forest.join(e.a, e.b_flip & 0x7FFFFFFFu, e.b_flip >> 31) && ++joins == n - 1) break;
  }
  std::vector<SignedEdge>().swap(edges);

  // Every point's flip relative to its piece's root (after this, a find is one step).
  std::vector<std::uint32_t> root(n);
  std::vector<unsigned char> flip(n);
  for (std::size_t i = 0; i < n; ++i) {
    const SignedUnionFind::Root r = forest.find(static_cast<std::uint32_t>(i));
    root[i] = r.root;
    flip[i] = static_cast<unsigned char>(r.flip);
  }
  // Each piece's vote, in point order so that the sum does not depend on the thread count.
  const Vec3 centre = points.colwise().mean().transpose();
  std::vector<double> vote(n, 0.0);
  for (std::size_t i = 0; i < n; ++i) {
    const Eigen::Index r = static_cast<Eigen::Index>(i);
    const double v = normals.row(r).dot(points.row(r) - centre.transpose());
    vote[root[i]] += flip[i] ? -v : v;
  }
  parallel_for(n, [&](std::size_t b, std::size_t e) {
    for (std::size_t i = b; i < e; ++i)
      if ((flip[i] != 0) != (vote[root[i]] < 0.0)) normals.row(static_cast<Eigen::Index>(i)) *= -1.0;
  }, {}, 4096);
}

}  // namespace pointscale
