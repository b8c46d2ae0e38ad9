#include "pointscale/normal_estimation.h"

#include <cmath>
#include <queue>

#include "pointscale/plane_fit.h"
#include "pointscale/self_knn.h"

namespace pointscale {

Points pca_normals(const SpatialIndex& index, int k, const ProgressStage& stage) {
  const Index n = index.size();
  k = std::min<int>(k, n);
  Points normals = Points::Zero(n, 3);  // rows stay zero only when k < 1
  const Points& p = index.points();
  std::vector<double> w(static_cast<std::size_t>(k), 1.0);
  self_knn(index, k, [&](Index i, const Index* idx, const double*, int found) {
    const PlaneFit fit = fit_weighted_plane(p, idx, w.data(), found, p.row(i).transpose());
    normals.row(i) = (fit.ok ? fit.normal : Vec3(Vec3::Zero())).transpose();
  }, stage);
  return normals;
}

void orient_normals(const SpatialIndex& index, Points& normals, int k) {
  const Index n = index.size();
  if (n == 0) return;
  const IndexList graph = knn_graph(index, k);
  k = static_cast<int>(graph.size() / n);
  const Points& p = index.points();
  const Vec3 centre = p.colwise().mean().transpose();
  // Seeds in order of decreasing distance from the centroid.
  std::vector<Index> order(n);
  Eigen::VectorXd dist(n);
  for (Index i = 0; i < n; ++i) { order[i] = i; dist(i) = (p.row(i).transpose() - centre).squaredNorm(); }
  std::sort(order.begin(), order.end(), [&](Index a, Index b) { return dist(a) > dist(b); });

  // Symmetric adjacency, so that propagation can cross edges found from either side.
  std::vector<std::vector<Index>> adj(n);
  for (Index i = 0; i < n; ++i)
    for (int j = 1; j < k; ++j) {
      const Index o = graph[static_cast<std::size_t>(i) * k + j];
      if (o == i) continue;
      adj[i].push_back(o);
      adj[o].push_back(i);
    }

  std::vector<unsigned char> visited(n, 0);
  using Item = std::pair<double, std::pair<Index, Index>>;  // (cost, (from, to))
  std::priority_queue<Item, std::vector<Item>, std::greater<Item>> heap;
  auto visit = [&](Index i) {
    visited[i] = 1;
    for (Index o : adj[i])
      if (!visited[o]) heap.push({1.0 - std::abs(normals.row(i).dot(normals.row(o))), {i, o}});
  };
  std::vector<Index> component;
  for (Index seed : order) {
    if (visited[seed]) continue;
    component.assign(1, seed);
    visit(seed);
    while (!heap.empty()) {
      const auto [cost, edge] = heap.top();
      heap.pop();
      const auto [from, to] = edge;
      if (visited[to]) continue;
      if (normals.row(from).dot(normals.row(to)) < 0.0) normals.row(to) *= -1.0;
      visit(to);
      component.push_back(to);
    }
    // Outward by a vote of the whole component, not by the seed alone: the farthest point is
    // often an outlier whose normal lies nearly in the tangent plane.
    double vote = 0.0;
    for (Index i : component) vote += normals.row(i).dot(p.row(i) - centre.transpose());
    if (vote < 0.0)
      for (Index i : component) normals.row(i) *= -1.0;
  }
}

}  // namespace pointscale
