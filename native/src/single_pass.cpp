#include "pointscale/single_pass.h"
#include "pointscale/validation.h"

#include <algorithm>
#include <vector>

#include "pointscale/detail/candidate_plane.h"
#include "pointscale/parallel.h"
#include "pointscale/sample_spacing.h"
#include "pointscale/spatial_order.h"
#include "pointscale/detail/support_neighbours.h"

namespace pointscale {

namespace {

// Fits point p's plane from its neighbours `nearest` (closest first, k of them), and with
// `estimate` the iteration's second step, and writes row i of the result.
struct Fitter {
  const SpatialIndex& support;
  const Eigen::VectorXd& h;
  const Eigen::VectorXd& inv_h2;
  SinglePassResult& out;
  std::vector<unsigned char>& degenerate;
  bool estimate;
  CandidateSet set;
  std::vector<Index> again;      // with estimate: the k nearest of the foot
  std::vector<double> again_d2;

  // The candidates relative to p, as fit_nearest_plane takes them. Exactly some point's k
  // nearest, so that it keeps them all (its prefix test holds).
  void gather(const Vec3& p, const Index* nearest, int count) {
    const Points& s = support.points();
    set.resize(count);
    for (int j = 0; j < count; ++j) {
      const Index c = nearest[j];
      set.x[j] = s(c, 0) - p.x(); set.y[j] = s(c, 1) - p.y(); set.z[j] = s(c, 2) - p.z();
      set.h[j] = h(c);
      set.inv_h2[j] = inv_h2(c);
      set.extra[j] = 0.0;
    }
  }

  void operator()(Eigen::Index i, const Vec3& p, const Index* nearest, int count) {
    gather(p, nearest, count);
    double nearest_h = 0.0, kth_d2 = 0.0;
    const PlaneFit fit = fit_nearest_plane(set, count, Vec3::Zero(), nearest_h, kth_d2);
    if (!fit.ok) {
      out.positions.row(i) = p.transpose();
      out.normals.row(i).setZero();
      out.moved(i) = 0.0;
      if (estimate) out.next_step(i) = 0.0;
      degenerate[static_cast<std::size_t>(i)] = 1;
      return;
    }
    const Vec3 foot = fit.mean.dot(fit.normal) * fit.normal;  // p projected onto the plane, relative to p
    out.positions.row(i) = (p + foot).transpose();
    out.normals.row(i) = fit.normal.transpose();
    out.moved(i) = foot.norm() / nearest_h;
    if (!estimate) return;
    // The iteration's second step exactly: the plane of the foot's own k nearest, weighted
    // from the foot, and p projected onto it. A query per point more, so only when asked.
    again.resize(static_cast<std::size_t>(count));
    again_d2.resize(static_cast<std::size_t>(count));
    const Vec3 at = p + foot;
    const int found = support.knn(at.data(), count, again.data(), again_d2.data());
    gather(p, again.data(), found);
    double next_h = 0.0;
    const PlaneFit next = fit_nearest_plane(set, found, foot, next_h, kth_d2);
    out.next_step(i) = next.ok ? (next.mean.dot(next.normal) * next.normal - foot).norm() / next_h : 0.0;
  }
};

}  // namespace

SinglePassResult mls_single_pass(const Points& x, bool self, const SpatialIndex& support, double kernel, int k,
                                 bool estimate, const ProgressStage& stage) {
  check_kernel(kernel);
  check_neighbors(k);
  check_points(x, "points");
  const Eigen::Index n = x.rows();
  self = self && n == support.size();
  k = std::min<int>(k, support.size());
  SinglePassResult out;
  out.positions.resize(n, 3);
  out.normals.resize(n, 3);
  out.moved.resize(n);
  if (estimate) out.next_step.resize(n);
  std::vector<unsigned char> degenerate(static_cast<std::size_t>(n), 0);
  Eigen::VectorXd h;
  if (self) {
    // One pass of the grid's self-queries gives each point's neighbours and its spacing (the
    // first 14 entries of a row are the ones local_spacing asks for: the same values).
    Eigen::VectorXd spacing;
    const SupportNeighbours rows = support_neighbours(support, std::max(k, 14), 6, &spacing);
    if (support.size() > 0 && !(spacing(0) > 0.0)) spacing = local_spacing(support, 6);  // all duplicates
    h = kernel * spacing;
    const Eigen::VectorXd inv_h2 = h.array().square().inverse();
    parallel_for(static_cast<std::size_t>(n), [&](std::size_t b, std::size_t e) {
      Fitter fit{support, h, inv_h2, out, degenerate, estimate, {}, {}, {}};
      for (std::size_t i = b; i < e; ++i)
        fit(static_cast<Eigen::Index>(i), x.row(static_cast<Eigen::Index>(i)).transpose(),
            rows.nearest.data() + i * static_cast<std::size_t>(rows.width), k);
    }, stage.sub(0.5, 1.0), 1024);
  } else {
    h = kernel * local_spacing(support, 6);
    const Eigen::VectorXd inv_h2 = h.array().square().inverse();
    // In a spatial order, consecutive queries visit the same branches of the tree.
    const IndexList order = morton_order(x);
    parallel_for(static_cast<std::size_t>(n), [&](std::size_t b, std::size_t e) {
      Fitter fit{support, h, inv_h2, out, degenerate, estimate, {}, {}, {}};
      std::vector<Index> nearest(static_cast<std::size_t>(k));
      std::vector<double> d2(static_cast<std::size_t>(k));
      for (std::size_t t = b; t < e; ++t) {
        const auto i = static_cast<Eigen::Index>(order[t]);
        const Vec3 p = x.row(i).transpose();
        const int found = support.knn(p.data(), k, nearest.data(), d2.data());
        fit(i, p, nearest.data(), found);
      }
    }, stage, 1024);
  }
  for (unsigned char d : degenerate) out.degenerate += d;
  return out;
}

}  // namespace pointscale
