#include "pointscale/encoding.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include "pointscale/cluster_decimation.h"
#include "pointscale/normal_estimation.h"
#include "pointscale/parallel.h"
#include "pointscale/plane_fit.h"
#include "pointscale/sample_spacing.h"

namespace pointscale {

LevelSupport build_level_support(const Points& fine, const Points& level, std::size_t target, double kernel,
                                 int neighbors, double max_variation) {
  Clustering clusters = cluster_decimate(level, target, max_variation);
  LevelSupport support;
  support.labels = std::move(clusters.labels);
  support.clusters = static_cast<Index>(clusters.centroids.rows());
  support.neighbors = std::min<int>(neighbors, support.clusters);
  choose_anchors(fine, level, support);
  const Points centroids = support_centroids(level, support);
  const SpatialIndex index(centroids);
  support.h = kernel * local_spacing(index, 6);
  support.neighborhoods = knn_graph(index, support.neighbors);
  attach_frames(centroids, level, support);
  return support;
}

Points orientation_reference(const Points& level, const LevelSupport& support) {
  const Points c = support_centroids(level, support);
  std::vector<Index> own(static_cast<std::size_t>(support.clusters));
  for (Index i = 0; i < support.clusters; ++i) own[i] = i;
  Points cn = support_normals(c, own.data(), c, support, Points::Zero(support.clusters, 3));
  orient_normals(SpatialIndex(c), cn, std::min<int>(16, support.clusters));
  Points reference(level.rows(), 3);
  for (Eigen::Index i = 0; i < level.rows(); ++i) reference.row(i) = cn.row(support.labels[i]);
  return reference;
}

MlsResult project_from_afar(const Points& x, const SpatialIndex& base, const Eigen::VectorXd& h,
                            const MlsOptions& options, const ProgressStage& stage) {
  const Eigen::Index n = x.rows();
  const int k = std::min<int>(options.neighbors, base.size());
  const Points& s = base.points();
  const Eigen::VectorXd inv_h2 = h.array().square().inverse();
  const int cap = std::max(options.max_iterations, 200);
  MlsResult out;
  out.positions.resize(n, 3);
  out.normals.resize(n, 3);
  std::vector<unsigned char> failed(n, 0), degenerate(n, 0);
  parallel_for(static_cast<std::size_t>(n), [&](std::size_t b, std::size_t e) {
    std::vector<Index> idx(k);
    std::vector<double> d2(k), ih2(k), w(k);
    for (std::size_t ii = b; ii < e; ++ii) {
      const Eigen::Index i = static_cast<Eigen::Index>(ii);
      const Vec3 p = x.row(i).transpose();
      base.knn(p.data(), 1, idx.data(), d2.data());
      Vec3 foot = s.row(idx[0]).transpose(), normal = Vec3::Zero(), last_foot = foot, last_normal = Vec3::Zero();
      bool ok = false, converged = false;
      double last_step = std::numeric_limits<double>::infinity(), safety = 1.0;
      for (int it = 0; it < cap; ++it) {
        const int found = base.knn(foot.data(), k, idx.data(), d2.data());
        for (int j = 0; j < found; ++j) ih2[j] = inv_h2(idx[j]);
        gaussian_weights(d2.data(), ih2.data(), found, w.data());
        const PlaneFit fit = fit_weighted_plane(s, idx.data(), w.data(), found, foot);
        if (!fit.ok) break;
        normal = fit.normal;
        if (ok && normal.dot(last_normal) < 0.0) normal = -normal;
        // The plain step swings with slope -(distance x curvature); the curvature seen between
        // the last two feet turns it into a Newton step, 1 / (1 + distance x curvature).
        double damping = 1.0;
        const double moved = (foot - last_foot).norm();
        if (ok && moved > 0.0) damping = 1.0 / (1.0 + std::abs((p - foot).dot(normal)) * (normal - last_normal).norm() / moved);
        ok = true;
        const Vec3 next = p - (p - fit.mean).dot(normal) * normal;
        const double step = (next - foot).norm();
        if (step > last_step) safety = std::max(safety * 0.5, 1.0 / 1024.0);
        last_step = step;
        last_foot = foot;
        last_normal = normal;
        foot += std::min(damping, safety) * (next - foot);
        // Keep the foot on the fitted plane while it moves in damped steps.
        foot -= (foot - fit.mean).dot(normal) * normal;
        if (step <= options.tolerance * h(idx[0])) { converged = true; break; }
      }
      out.positions.row(i) = foot.transpose();
      out.normals.row(i) = normal.transpose();
      if (!ok) degenerate[ii] = 1;
      else if (!converged) failed[ii] = 1;
    }
  }, stage, 64);
  for (Eigen::Index i = 0; i < n; ++i) { out.not_converged += failed[i]; out.degenerate += degenerate[i]; }
  return out;
}

Points oriented_normals(const SpatialIndex& base) {
  const int k = std::min<int>(16, base.size());
  Points normals = pca_normals(base, k);
  orient_normals(base, normals, k);
  return normals;
}

Points nearest_normals(const Points& query, const SpatialIndex& base, const Points& base_normals) {
  Points out(query.rows(), 3);
  parallel_for(static_cast<std::size_t>(query.rows()), [&](std::size_t b, std::size_t e) {
    Index nearest;
    double d2;
    for (std::size_t ii = b; ii < e; ++ii) {
      const Eigen::Index i = static_cast<Eigen::Index>(ii);
      base.knn(query.row(i).data(), 1, &nearest, &d2);
      out.row(i) = base_normals.row(nearest);
    }
  }, {}, 1024);
  return out;
}

namespace {

// Moves p along the unit direction d onto the MLS surface: two ray-plane steps (Adamson and
// Alexa 2003), enough for a point that slid a little off it within its tangent plane.
Vec3 along_onto(const Vec3& p, const Vec3& d, const SpatialIndex& surface, const Eigen::VectorXd& h, int k) {
  k = std::min<int>(k, surface.size());
  Index idx[64];
  double d2[64], ih2[64], w[64];
  k = std::min(k, 64);
  Vec3 x = p;
  for (int it = 0; it < 2; ++it) {
    const int found = surface.knn(x.data(), k, idx, d2);
    for (int j = 0; j < found; ++j) ih2[j] = 1.0 / (h(idx[j]) * h(idx[j]));
    gaussian_weights(d2, ih2, found, w);
    const PlaneFit fit = fit_weighted_plane(surface.points(), idx, w, found, x);
    const double cosine = fit.ok ? fit.normal.dot(d) : 0.0;
    if (std::abs(cosine) < 0.5) return x;  // the surface turns away here: stay
    x += ((fit.mean - x).dot(fit.normal) / cosine) * d;
  }
  return x;
}

}  // namespace

Alignment align_offsets(const Points& fine, Points& level, const LevelSupport& support, const Points& reference,
                        int max_iterations, double stop, const ProgressStage& stage, const SpatialIndex* surface,
                        const Eigen::VectorXd* surface_h, int surface_neighbors) {
  auto settle = [&](const Vec3& p, const Vec3& n) {
    return surface ? along_onto(p, n, *surface, *surface_h, surface_neighbors) : p;
  };
  const Points start = level;
  // How far a point may slide: its cluster's kernel width, or a twentieth of its offset (a 3 degree
  // turn of its normal line), whichever is more. The level leaves the base by move^2 curvature / 2.
  auto reach = [&](Eigen::Index i, Index c) {
    return std::max(support.h(c), 0.05 * (fine.row(i) - start.row(i)).norm());
  };
  const Index c_count = support.clusters;
  std::vector<unsigned char> kept(static_cast<std::size_t>(c_count), 0);
  std::vector<Index> own(static_cast<std::size_t>(c_count));
  Points anchor_reference(c_count, 3);
  for (Index c = 0; c < c_count; ++c) { own[c] = c; anchor_reference.row(c) = reference.row(support.anchors[c]); }
  std::vector<double> moves(c_count, std::numeric_limits<double>::infinity()), damping(c_count, 1.0);
  {
    // Moving an anchor by u turns its normal by about u x curvature and its target by
    // detail x curvature x u the other way: start from the Newton step 1 / (1 + |detail| x curvature),
    // with the curvature from the normals of the neighbouring anchors.
    const Points anchors = support_centroids(level, support);
    const Points normals = support_normals(anchors, own.data(), anchors, support, anchor_reference);
    const int k = support.neighbors;
    for (Index c = 0; c < c_count; ++c) {
      // A ratio of sums: nearly coincident anchors must not blow the estimate up.
      double turn = 0.0, span = 0.0;
      const Index* nb = support.neighborhoods.data() + static_cast<std::size_t>(c) * k;
      for (int j = 1; j < k; ++j) {
        span += (anchors.row(nb[j]) - anchors.row(c)).norm();
        turn += (normals.row(nb[j]) - normals.row(c)).norm();
      }
      const double curvature = span > 0 ? turn / span : 0.0;
      const double detail = (fine.row(support.anchors[c]) - level.row(support.anchors[c])).norm();
      damping[c] = 1.0 / (1.0 + detail * curvature);
    }
  }
  const std::vector<double> newton = damping;
  double largest = std::numeric_limits<double>::infinity();
  int it = 0;
  for (; it < max_iterations && largest > stop; ++it) {
    stage.report(static_cast<double>(it) / max_iterations);
    const Points anchors = support_centroids(level, support);
    const Points normals = support_normals(anchors, own.data(), anchors, support, anchor_reference);
    parallel_for(static_cast<std::size_t>(c_count), [&](std::size_t b, std::size_t e) {
      for (std::size_t c = b; c < e; ++c) {
        if (kept[c]) { moves[c] = 0.0; continue; }
        const Index i = support.anchors[c];
        const Vec3 nrm = normals.row(static_cast<Eigen::Index>(c)).transpose();
        const Vec3 f = fine.row(i).transpose();
        const Vec3 p = level.row(i).transpose();
        const Vec3 target = f - (f - p).dot(nrm) * nrm;
        const Vec3 move = target - p;
        const double full = move.norm();
        // A growing move means the step is too long: halve it. A shrinking one lets it grow back
        // towards the Newton step, so that noise in the neighbours' moves cannot stall an anchor.
        if (full > 1.1 * moves[c]) damping[c] = std::max(damping[c] * 0.5, 1.0 / 1024.0);
        else if (full < moves[c]) damping[c] = std::min(newton[c], damping[c] * 1.25);
        moves[c] = full;
        // A slide m leaves the surface by about m^2 curvature / 2: only larger ones need the step back.
        const Vec3 slid = p + damping[c] * move;
        level.row(i) = (damping[c] * full > 1e-3 * support.h(static_cast<Eigen::Index>(c)) ? settle(slid, nrm) : slid).transpose();
        if ((level.row(i) - start.row(i)).norm() > reach(i, support.labels[i])) {
          level.row(i) = start.row(i);
          kept[c] = 1;
          moves[c] = 0.0;
        }
      }
    });
    largest = *std::max_element(moves.begin(), moves.end());
  }
  Alignment out;
  out.iterations = it;
  const Points normals = level_normals(level, support, reference);
  std::vector<unsigned char> is_anchor(static_cast<std::size_t>(level.rows()), 0);
  for (Index a : support.anchors) is_anchor[a] = 1;
  std::vector<unsigned char> stays(static_cast<std::size_t>(level.rows()), 0);
  std::vector<double> left(static_cast<std::size_t>(level.rows()), 0.0);
  parallel_for(static_cast<std::size_t>(level.rows()), [&](std::size_t b, std::size_t e) {
    for (std::size_t ii = b; ii < e; ++ii) {
      const Eigen::Index i = static_cast<Eigen::Index>(ii);
      const Vec3 nrm = normals.row(i).transpose();
      const Vec3 f = fine.row(i).transpose();
      if (!is_anchor[ii]) {
        const Vec3 target = f - (f - level.row(i).transpose()).dot(nrm) * nrm;
        if ((target - start.row(i).transpose()).norm() <= reach(i, support.labels[ii]))
          level.row(i) = settle(target, nrm).transpose();
        else stays[ii] = 1;
      }
      const Vec3 d = f - level.row(i).transpose();
      left[ii] = (d - d.dot(nrm) * nrm).norm();
    }
  });
  for (Index c = 0; c < c_count; ++c) out.kept += kept[c];
  for (unsigned char s : stays) out.kept += s;
  out.residual = *std::max_element(left.begin(), left.end());
  stage.report(1.0);
  return out;
}

MultiscaleModel encode_onto(const Points& points, const Points& base, const Points* base_normals,
                            const EncodeOptions& options, const ProgressCallback* progress) {
  const ProgressStage all{progress, 0.0, 1.0};
  const Eigen::Index n = points.rows();
  const double scale = (points.colwise().maxCoeff() - points.colwise().minCoeff()).norm();
  const SpatialIndex base_index(base);
  const Eigen::VectorXd h = options.kernel * local_spacing(base_index, 6);
  MlsResult projected = project_from_afar(points, base_index, h, options.mls, all.sub(0.0, 0.6));

  // The level's own support, about as fine as the base (and never finer than the model).
  const auto target = static_cast<std::size_t>(std::min<Eigen::Index>(base.rows(), std::max<Eigen::Index>(1, n / 2)));
  MultiscaleModel model;
  model.support.push_back(build_level_support(points, projected.positions, target, options.kernel,
                                              options.mls.neighbors, options.max_variation));
  const LevelSupport& support = model.support[0];
  Points level = std::move(projected.positions);

  // Orientation from the base: its given normals, else outward by propagation over the base.
  const Points reference = nearest_normals(level, base_index, base_normals ? *base_normals : oriented_normals(base_index));

  const Alignment aligned = align_offsets(points, level, support, reference, options.consistency_iterations,
                                         1e-12 * scale, all.sub(0.6, 0.95), &base_index, &h, options.mls.neighbors);
  const Points normals = level_normals(level, support, reference);
  model.details.resize(1, n);
  for (Eigen::Index i = 0; i < n; ++i) model.details(0, i) = (points.row(i) - level.row(i)).dot(normals.row(i));
  model.base_normals = normals;
  model.base = std::move(level);
  LevelReport report;
  report.support_points = static_cast<std::size_t>(support.clusters);
  report.kernel_width = h.size() ? h.mean() : 0.0;
  report.not_converged = projected.not_converged;
  report.degenerate = projected.degenerate;
  report.consistency_iterations = aligned.iterations;
  report.consistency_residual = aligned.residual;
  report.pinned = aligned.kept;
  model.reports.push_back(report);
  all.report(1.0);
  return model;
}

}  // namespace pointscale
