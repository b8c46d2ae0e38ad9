#include "pointscale/cluster_decimation.h"

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <queue>

namespace pointscale {

namespace {

struct Cluster {
  std::size_t begin, end;  // range in the permutation
  Vec3 centroid;
  Vec3 axis;               // direction of largest covariance
  double priority;
  bool splittable;
  bool operator<(const Cluster& o) const { return priority < o.priority; }
};

Cluster describe(const Points& p, const std::vector<Index>& perm, std::size_t b, std::size_t e,
                 double max_variation) {
  Cluster c{b, e, Vec3::Zero(), Vec3::Zero(), 0.0, false};
  const double count = static_cast<double>(e - b);
  const Vec3 ref = p.row(perm[b]).transpose();
  Vec3 s = Vec3::Zero();
  Mat3 ss = Mat3::Zero();
  for (std::size_t i = b; i < e; ++i) {
    const Vec3 d = p.row(perm[i]).transpose() - ref;
    s += d;
    ss.noalias() += d * d.transpose();
  }
  const Vec3 m = s / count;
  c.centroid = ref + m;
  const Mat3 cov = ss / count - m * m.transpose();
  Eigen::SelfAdjointEigenSolver<Mat3> eig;
  eig.computeDirect(cov);
  const Vec3 ev = eig.eigenvalues();
  const double trace = ev.sum();
  c.axis = eig.eigenvectors().col(2);
  c.splittable = (e - b) > 1 && trace > 0.0;
  const double variation = trace > 0.0 ? std::max(0.0, ev(0)) / trace : 0.0;
  c.priority = count * (variation > max_variation ? 4.0 : 1.0);
  return c;
}

}  // namespace

Clustering cluster_decimate(const Points& points, std::size_t target, double max_variation) {
  const std::size_t n = static_cast<std::size_t>(points.rows());
  target = std::max<std::size_t>(1, std::min(target, n));
  std::vector<Index> perm(n);
  for (std::size_t i = 0; i < n; ++i) perm[i] = static_cast<Index>(i);

  std::priority_queue<Cluster> open;
  std::vector<Cluster> done;
  open.push(describe(points, perm, 0, n, max_variation));
  while (!open.empty() && open.size() + done.size() < target) {
    Cluster c = open.top();
    open.pop();
    if (!c.splittable) { done.push_back(c); continue; }
    auto mid = std::partition(perm.begin() + c.begin, perm.begin() + c.end, [&](Index i) {
      return (points.row(i).transpose() - c.centroid).dot(c.axis) < 0.0;
    });
    const std::size_t m = static_cast<std::size_t>(mid - perm.begin());
    if (m == c.begin || m == c.end) { c.splittable = false; done.push_back(c); continue; }
    open.push(describe(points, perm, c.begin, m, max_variation));
    open.push(describe(points, perm, m, c.end, max_variation));
  }
  while (!open.empty()) { done.push_back(open.top()); open.pop(); }

  // Deterministic order: by position in the permutation.
  std::sort(done.begin(), done.end(), [](const Cluster& a, const Cluster& b) { return a.begin < b.begin; });
  Clustering out;
  out.centroids.resize(static_cast<Eigen::Index>(done.size()), 3);
  out.labels.assign(n, 0);
  for (std::size_t c = 0; c < done.size(); ++c) {
    out.centroids.row(static_cast<Eigen::Index>(c)) = done[c].centroid.transpose();
    for (std::size_t i = done[c].begin; i < done[c].end; ++i) out.labels[perm[i]] = static_cast<Index>(c);
  }
  return out;
}

}  // namespace pointscale
