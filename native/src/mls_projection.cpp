#include "pointscale/mls_projection.h"
#include "pointscale/detail/mls_hints.h"

#include <algorithm>
#include <cmath>
#include <utility>
#include <limits>
#include <stdexcept>

#include "pointscale/detail/candidate_plane.h"
#include "pointscale/normal_estimation.h"
#include "pointscale/parallel.h"
#include "pointscale/spatial_order.h"
#include "pointscale/detail/thin_sheets.h"
#include "pointscale/validation.h"

namespace pointscale {

MlsResult mls_project(const Points& x, const SpatialIndex& support, const Eigen::VectorXd& h,
                      const MlsOptions& options, const ProgressStage& stage) {
  return mls_project(x, support, h, options, MlsHints{}, stage);
}

MlsResult mls_project(const Points& x, const SpatialIndex& support, const Eigen::VectorXd& h,
                      const MlsOptions& options, const MlsHints& hints, const ProgressStage& stage) {
  const Eigen::Index n = x.rows();
  validate(options);
  check_points(x, "points");
  if (h.size() != support.size()) throw std::invalid_argument("h must hold one kernel width per support point");
  // An optional input of the wrong size is an error, not a reason to go without it.
  const auto un = static_cast<std::size_t>(n);
  if (options.order && options.order->size() != un)
    throw std::invalid_argument("MlsOptions.order must list every point once");
  if (options.near_support && options.near_support->size() != un)
    throw std::invalid_argument("MlsOptions.near_support must have one entry per point");
  if (options.near_support) check_near_support(*options.near_support, n, support.size());
  check_normals(options.support_normals, support.points(), "onto_normals", "onto");
  if (!hints.point_sides != !hints.support_sides ||
      (hints.point_sides && (hints.point_sides->rows() != n || hints.support_sides->rows() != support.size())))
    throw std::invalid_argument("MlsHints: the sides of every point and every support point, or neither");
  const int k = std::min<int>(options.neighbors, support.size());
  const Points& s = support.points();
  const Eigen::VectorXd inv_h2 = h.array().square().inverse();
  // Anisotropic weights: |d|^2 + (1/sheet^2 - 1)(n.d)^2 in place of |d|^2.
  Points estimated;
  const Points* sheet_normals = options.support_normals;
  if (!sheet_normals && options.thin_sheets) {
    estimated = pca_normals(support, std::min<int>(16, support.size()));
    sheet_normals = &estimated;
  }
  const double sheet_extra = sheet_normals ? 1.0 / (options.sheet * options.sheet) - 1.0 : 0.0;
  const bool sides = hints.point_sides != nullptr;
  MlsResult out;
  out.positions.resize(n, 3);
  out.normals.resize(n, 3);
  std::vector<unsigned char> failed(n, 0), degenerate(n, 0);

  // A kd-tree query returns the kc > k support points nearest to a centre, all of them within
  // its radius R. They hold the k nearest of any position x with |x - centre| + d_k(x) < R,
  // d_k(x) the k-th distance among them: those are then x's k nearest (the ball of radius
  // d_k(x) around x lies inside R). So one query serves the foot while it moves, and, points
  // coming in Morton order, the points after it, until that test fails. The neighbours are
  // always those of a fresh query. With a support point near each point (decompose passes each
  // point's cluster), the query is centred there instead, and serves the points around it,
  // which takes fewer queries than the Morton order. Decompose also hands over the support's
  // rows (support_neighbours.h, detail/mls_hints.h), which answer the queries centred on
  // support points without the tree.
  const IndexList* near = options.near_support;
  // Centred on a support point, a query must reach past the k nearest of every point around it.
  // With sides, about half the candidates face the other way: ask for twice as many.
  const int kc = std::min<int>(sides ? 2 * k + near_query_extra : near ? k + near_query_extra : k + 8, support.size());
  // The caller's rows serve only when they are as wide as this projection's queries (with sides
  // they are not: the tree answers).
  const SupportNeighbours* rows = near && hints.near_rows && hints.near_rows->width == kc &&
                                          hints.near_rows->reach.size() == support.size()
                                      ? hints.near_rows : nullptr;
  const bool given = options.order != nullptr;
  const IndexList own_order = given ? IndexList() : morton_order(x);
  const IndexList& order = given ? *options.order : own_order;
  const double everything = std::numeric_limits<double>::infinity();
  parallel_for(static_cast<std::size_t>(n), [&](std::size_t b, std::size_t e) {
    std::vector<Index> cand(kc);
    std::vector<double> cand_d2(kc);
    CandidateSet set;
    int candidates = 0;
    Vec3 centre = Vec3::Zero();
    double radius = 0.0;
    bool gathered = false;  // the set holds the candidates of the last query
    auto query = [&](const Vec3& at) {
      candidates = support.knn(at.data(), kc, cand.data(), cand_d2.data());
      centre = at;
      radius = candidates < kc || kc == support.size() ? everything : std::sqrt(cand_d2[candidates - 1]);
      gathered = false;
    };
    // The query centred on support point c, from its row when the caller made them.
    auto query_at_support = [&](Index c) {
      if (!rows) return query(s.row(c).transpose());
      candidates = kc;
      std::copy_n(rows->nearest.data() + static_cast<std::size_t>(c) * kc, kc, cand.data());
      centre = s.row(c).transpose();
      radius = rows->reach(c);
      gathered = false;
    };
    // The candidates relative to `origin`, in the order of the query (nearest to its centre
    // first): fit_nearest_plane finds the k nearest of the foot at the front when the foot is
    // near the centre, and sorts them out itself otherwise. Without thin sheets the origin is
    // the query's centre, so the points a query serves share one gathering; with them it is
    // each point, which the sheets' weights are measured from.
    Vec3 origin = Vec3::Zero();
    Vec3 side = Vec3::Zero();  // the side of the point being projected, with sides
    auto gather = [&](const Vec3& p) {
      if (!sheet_normals && !sides && gathered) return;
      origin = sheet_normals ? p : centre;
      gathered = true;
      int kept = 0;
      for (int j = 0; j < candidates; ++j)
        kept += !sides || same_side(hints.support_sides->row(cand[j]).dot(side));
      set.resize(kept);
      for (int j = 0, jj = 0; jj < candidates; ++jj) {
        const Index c = cand[jj];
        if (sides && !same_side(hints.support_sides->row(c).dot(side))) continue;
        set.x[j] = s(c, 0) - origin.x(); set.y[j] = s(c, 1) - origin.y(); set.z[j] = s(c, 2) - origin.z();
        set.h[j] = h(c);
        set.inv_h2[j] = inv_h2(c);
        // Measured from the point being projected, not the moving foot, so that the foot
        // cannot drift towards the other sheet and take the weights along.
        double along = 0.0;
        if (sheet_normals) along = sheet_normals->row(c).dot(s.row(c) - p.transpose());
        set.extra[j] = sheet_extra * along * along;
        ++j;
      }
    };
    for (std::size_t t = b; t < e; ++t) {
      const auto i = static_cast<std::size_t>(order[t]);
      const Vec3 p = x.row(static_cast<Eigen::Index>(i)).transpose();
      const Vec3 near_at = near ? Vec3(s.row((*near)[i]).transpose()) : p;
      if (sides) side = hints.point_sides->row(static_cast<Eigen::Index>(i)).transpose();
      if (candidates == 0) near ? query_at_support((*near)[i]) : query(p);
      gather(p);
      // The foot and the plane are kept relative to p; the candidates are relative to origin.
      Vec3 foot = Vec3::Zero();
      Vec3 normal = Vec3::Zero();
      bool converged = false, ok = false;
      double last_step = std::numeric_limits<double>::infinity(), damping = 1.0;
      double nearest_h = 0.0, kth_d2 = 0.0;
      auto fit_at_foot = [&] {
        const Vec3 offset = p - origin;
        PlaneFit fit = fit_nearest_plane(set, k, offset + foot, nearest_h, kth_d2);
        fit.mean -= offset;
        return fit;
      };
      for (int it = 0; it < options.max_iterations; ++it) {
        PlaneFit fit = fit_at_foot();
        auto holds = [&] { return radius == everything || (p + foot - centre).norm() + std::sqrt(kth_d2) < radius; };
        if (!holds() && near && it == 0 && centre != near_at) {
          query_at_support((*near)[i]);
          gather(p);
          fit = fit_at_foot();
        }
        if (!holds()) {
          query(p + foot);
          gather(p);
          fit = fit_at_foot();
        }
        if (!fit.ok) break;
        ok = true;
        normal = fit.normal;
        const Vec3 next = fit.mean.dot(normal) * normal;  // p projected onto the plane, relative to p
        const double step = (next - foot).norm();
        // Near sharp features the foot point can swing back and forth: damp a growing step.
        if (step > last_step) damping = std::max(damping * 0.5, 1.0 / 64.0);
        // With steps shrinking at a steady rate r, the foot is within r / (1 - r) x step of
        // where the iteration goes: stop once that is below the tolerance too (most points
        // get there a fit earlier than by their step alone).
        const double rate = it > 0 && damping == 1.0 ? step / last_step : 1.0;
        last_step = step;
        foot += damping * (next - foot);
        const double limit = options.tolerance * nearest_h;
        if (step <= limit || (rate < 0.5 && rate * step <= (1.0 - rate) * limit)) { converged = true; break; }
      }
      foot += p;
      out.positions.row(static_cast<Eigen::Index>(i)) = foot.transpose();
      out.normals.row(static_cast<Eigen::Index>(i)) = normal.transpose();
      if (!ok) degenerate[i] = 1;
      else if (!converged) failed[i] = 1;
    }
  }, stage, 1024);
  for (Eigen::Index i = 0; i < n; ++i) { out.not_converged += failed[i]; out.degenerate += degenerate[i]; }
  return out;
}

}  // namespace pointscale
