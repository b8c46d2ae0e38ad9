#include "pointscale/decomposition.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numeric>
#include <utility>

#include "pointscale/cluster_decimation.h"
#include "pointscale/normal_estimation.h"
#include "pointscale/parallel.h"
#include "pointscale/release_memory.h"
#include "pointscale/renumber_points.h"
#include "pointscale/sample_spacing.h"
#include "pointscale/spatial_index.h"
#include "pointscale/spatial_order.h"
#include "pointscale/support_neighbours.h"
#include "pointscale/thin_sheets.h"

namespace pointscale {

namespace {

double median(Eigen::VectorXd v) {
  if (v.size() == 0) return 0.0;
  std::nth_element(v.data(), v.data() + v.size() / 2, v.data() + v.size());
  return v(v.size() / 2);
}

using FloatNormals = Eigen::Matrix<float, Eigen::Dynamic, 3, Eigen::RowMajor>;

// Per point, the sign of n_finer . n (-1, 0 or 1): the finer level's normals, held in single
// precision, against the unoriented normals of the level below it. Single precision tells the
// sign wherever the dot product is not near 0; there the finer level's normals are evaluated
// again, exactly, for the clusters concerned (anchor_normals_of_clusters: bitwise as before).
// finer_anchors #C by 3 and finer: the finer level's anchors and support.
// original: the points' input numbers, by which finer.local lists each cluster's points.
std::vector<signed char> turn_signs(const FloatNormals& finer_normals, const Points& finer_anchors,
                                    const LevelSupport& finer, const Points& normals, const IndexList& original) {
  const Eigen::Index n = normals.rows();
  std::vector<signed char> turn(static_cast<std::size_t>(n));
  std::vector<unsigned char> unsure(static_cast<std::size_t>(n), 0);
  auto sign = [](double d) { return static_cast<signed char>((d > 0.0) - (d < 0.0)); };
  parallel_for(static_cast<std::size_t>(n), [&](std::size_t b, std::size_t e) {
    for (std::size_t ii = b; ii < e; ++ii) {
      const auto i = static_cast<Eigen::Index>(ii);
      const double d = finer_normals.row(i).cast<double>().dot(normals.row(i));
      turn[ii] = sign(d);
      unsure[ii] = std::abs(d) <= 1e-4;  // single precision is good to about 2e-7 here
    }
  }, {}, 4096);
  std::vector<unsigned char> recompute(static_cast<std::size_t>(finer.clusters), 0);
  bool any = false;
  for (Eigen::Index i = 0; i < n; ++i) if (unsure[i]) { recompute[finer.labels[i]] = 1; any = true; }
  if (!any) return turn;
  IndexList which;
  const Points exact = anchor_normals_of_clusters(finer_anchors, finer, recompute, which, &original);
  for (std::size_t j = 0; j < which.size(); ++j)
    if (unsure[which[j]]) turn[which[j]] = sign(exact.row(static_cast<Eigen::Index>(j)).dot(normals.row(which[j])));
  return turn;
}

struct Consistency {
  int iterations = 0;
  double residual = 0.0;
  std::size_t pinned = 0;
};

// Moves the points of level l-1 within their tangent planes until fine - p lies along n(p).
// Normals depend on the anchors only (level_support.h), so the anchors are iterated first,
// each halving its step when its move grows (near sharp features the plain iteration swings
// with slope about -d kappa). An anchor that still does not settle is pinned to its finer
// position (no detail in this band; the coarser bands carry it). Then every other point is made
// consistent in one step, since its normal no longer depends on it: exact by construction.
// anchor_reference #C by 3 orients the anchors' normals during the iteration. Writes each
// point's detail along its unoriented normal (the eigenvector's own sign) to details(i),
// and those normals to `normals`. layout: the points grouped the way support.local is laid out.
Consistency make_offsets_normal(const Points& fine, Points& level, const LevelSupport& support,
                                const LabelGroups& layout, const Points& anchor_reference, double scale,
                                int max_iterations, const ProgressStage& stage, Eigen::MatrixXd::RowXpr details,
                                Points& normals) {
  const double stop = 1e-12 * scale;
  const Index c_count = support.clusters;
  const int k = support.neighbors;
  const double never = std::numeric_limits<double>::infinity();
  std::vector<double> moves(c_count, never), damping(c_count, 1.0), earlier(c_count, never);
  std::vector<unsigned char> pinned(c_count, 0), active(c_count, 0);
  // The anchors to move next (flagged in `active`), listed so that an iteration costs in
  // proportion to them: a real scan takes hundreds of iterations over a few anchors each.
  std::vector<Index> woken;
  auto wake_all = [&] {
    woken.resize(static_cast<std::size_t>(c_count));
    std::iota(woken.begin(), woken.end(), 0);
    std::fill(active.begin(), active.end(), 1);
  };
  wake_all();
  std::vector<Index> todo;
  Points anchors = support_centroids(level, support);  // kept equal to the anchors' rows of level
  Consistency out;
  for (int round = 0;; ++round) {
    double largest = 0.0;
    bool settled = false;
    for (int it = 0; it < max_iterations; ++it, ++out.iterations) {
      stage.report(std::min(1.0, static_cast<double>(out.iterations) / (4.0 * max_iterations)));
      if (it == max_iterations / 2) earlier = moves;
      // Only anchors that moved, or whose neighbours moved, can move again; once none is left,
      // one sweep over all of them confirms that they have settled.
      std::sort(woken.begin(), woken.end());
      todo.clear();
      for (const Index c : woken) if (!pinned[c]) todo.push_back(c);
      const bool sweep = todo.empty();
      if (sweep) for (Index c = 0; c < c_count; ++c) if (!pinned[c]) todo.push_back(c);
      Points query(static_cast<Eigen::Index>(todo.size()), 3), query_reference(query.rows(), 3);
      for (std::size_t j = 0; j < todo.size(); ++j) {
        query.row(j) = anchors.row(todo[j]);
        query_reference.row(j) = anchor_reference.row(todo[j]);
      }
      const Points normals = support_normals_of(query, todo, anchors, support, query_reference);
      parallel_for(todo.size(), [&](std::size_t b, std::size_t e) {
        for (std::size_t j = b; j < e; ++j) {
          const Index c = todo[j];
          const Index i = support.anchors[c];
          const Vec3 nrm = normals.row(static_cast<Eigen::Index>(j)).transpose();
          const Vec3 f = fine.row(i).transpose();
          const Vec3 p = level.row(i).transpose();
          const Vec3 target = f - (f - p).dot(nrm) * nrm;
          const double full = (target - p).norm();
          // Halve the step while the move grows (a swing), regain it while the move shrinks.
          damping[c] = full > moves[c] ? std::max(damping[c] * 0.5, 1.0 / 64.0) : std::min(1.0, damping[c] * 1.5);
          moves[c] = full;
          level.row(i) = (p + damping[c] * (target - p)).transpose();
          anchors.row(c) = level.row(i);
        }
      });
      largest = 0.0;
      for (const Index c : woken) active[c] = 0;
      woken.clear();
      for (const Index c : todo) {
        if (!(moves[c] > stop)) continue;
        largest = std::max(largest, moves[c]);
        const Index* nb = support.neighborhoods.data() + static_cast<std::size_t>(c) * k;
        for (int j = 0; j < k; ++j)
          if (!active[nb[j]]) { active[nb[j]] = 1; woken.push_back(nb[j]); }
      }
      if (largest <= stop && sweep) { settled = true; break; }
      // A neighbour woken by another's move starts afresh: its small old move is no measure.
      for (const Index c : woken) if (moves[c] <= stop) moves[c] = never;
    }
    out.residual = largest;
    if (settled) break;
    // Pin the anchors that stopped settling over the second half of the round (all unsettled
    // ones after a few rounds) and let the others settle around them. Anchors that still
    // converge keep going, and from round 8 on every round pins at least one, so this ends.
    const bool last_chance = round >= 8;
    for (Index c = 0; c < c_count; ++c)
      if (!pinned[c] && moves[c] > stop && moves[c] < never && (last_chance || moves[c] > 0.25 * earlier[c])) {
        pinned[c] = 1;
        ++out.pinned;
        level.row(support.anchors[c]) = fine.row(support.anchors[c]);
        anchors.row(c) = level.row(support.anchors[c]);
      }
    std::fill(moves.begin(), moves.end(), never);
    wake_all();
  }
  Points().swap(anchors);  // level_normals takes its own copy
  // The iteration's temporaries go back to the system before the peak. This is the only trim
  // within a step: trims at its start and after the decimation lowered no peak, and the next
  // step's arrays faulted the same pages in again.
  release_free_memory();
  // Unoriented: the move below does not depend on the sign, and decompose orients the
  // normals (and flips these details with them) once level 0 is known.
  level_normals(level, support, Points(), {}, normals, &layout);
  std::vector<unsigned char> is_anchor(static_cast<std::size_t>(level.rows()), 0);
  for (Index a : support.anchors) is_anchor[a] = 1;
  parallel_for(static_cast<std::size_t>(level.rows()), [&](std::size_t b, std::size_t e) {
    for (std::size_t ii = b; ii < e; ++ii) {
      const Eigen::Index i = static_cast<Eigen::Index>(ii);
      const Vec3 nrm = normals.row(i).transpose();
      const Vec3 f = fine.row(i).transpose();
      if (!is_anchor[ii]) level.row(i) = (f - (f - level.row(i).transpose()).dot(nrm) * nrm).transpose();
      details(i) = (fine.row(i) - level.row(i)).dot(normals.row(i));
    }
  });
  stage.report(1.0);
  return out;
}

}  // namespace

MultiscaleModel decompose(Points points, const Points* input_normals, const DecomposeOptions& options,
                          const ProgressCallback* progress) {
  const Eigen::Index n = points.rows();
  const int k = options.levels - 1;
  const double scale = (points.colwise().maxCoeff() - points.colwise().minCoeff()).norm();
  const ProgressStage all{progress, 0.0, 1.0};
  const int kk = options.mls.neighbors;

  MultiscaleModel model;
  model.support.resize(k);
  model.reports.resize(k);
  // Only the level being built and the one it comes from are held; a finished level keeps its
  // detail along its unoriented normals, and how those turn against the next level's.
  Points fine = std::move(points);
  model.details.resize(k, n);
  // The level built last: its unoriented normals in single precision, and its anchors
  // (after the last step, level 0's, which orient it).
  FloatNormals finer_normals;
  Points finer_anchors;
  Points normals0;  // level 0's unoriented normals
  std::vector<std::vector<signed char>> turns(k);  // turns[l]: sign of n_l . n_{l-1} per point
  // From the first decimation on, the points are numbered in the order of its clusters, which is
  // a spatial one: point i is input point original[i]. Every per-point pass then walks memory in
  // order, whatever order the input comes in. Loops whose sums depend on the order (the decimation's splits, the projection's
  // query sharing, the anchors' ties) still visit the points in the input's order, so the model,
  // numbered back at the end, is bit for bit what the input's numbering gives.
  IndexList original;
  // Thin sheets: each point's oriented input normal tells the side of a wall it is on, at every
  // level (smoothing moves a point along its surface, never through the wall), in the points'
  // current numbering.
  const bool sheets = options.thin_sheets && input_normals && input_normals->rows() == n;
  Points sides;

  for (int step = 0; step < k; ++step) {
    const int l = k - step;  // builds level l-1 from level l
    const ProgressStage stage = all.sub(static_cast<double>(step) / (k + 0.2), static_cast<double>(step + 1) / (k + 0.2));
    stage.report(0.0);

    // Decimate P^l to Q^{l-1}: |Q^{l-1}| = gamma^(step+1) n (Sec. 5.2).
    const auto target = static_cast<std::size_t>(std::floor(std::pow(options.decimation, step + 1) * n));
    IndexList input_order;  // the points' current numbers in the input's order
    if (!original.empty()) input_order = inverse_order(original);
    const Points* side_normals = !sheets ? nullptr : original.empty() ? input_normals : &sides;
    Clustering clusters = cluster_decimate(fine, target, options.max_variation, original.empty() ? nullptr : &input_order,
                                           side_normals);
    const auto cluster_count = static_cast<Index>(clusters.centroids.rows());
    // Project P^l onto the MLS surface of Q^{l-1}, cluster by cluster, each cluster's points
    // around one query at its centroid (clusters come in a spatial order), in input order.
    LabelGroups groups = group_by_label(clusters.labels.data(), clusters.labels.size(), cluster_count,
                                        original.empty() ? nullptr : input_order.data());
    input_order = IndexList();
    if (step == 0) {
      original = number_by_groups(fine, clusters.labels, groups);
      if (sheets) sides = gather_rows(*input_normals, original);
      release_free_memory();  // the input's copy in its own numbering
    }
    // The points are in the first clusters' numbering by now, and so are the sides.
    const Points cluster_sides = sheets ? cluster_side_normals(sides, clusters.labels, cluster_count) : Points();
    if (options.diffusion) clusters.centroids = diffuse(clusters.centroids, *options.diffusion);
    stage.report(0.05);
    SpatialIndex q_index(clusters.centroids);
    // Each centroid's nearest centroids, asked once: its kernel width and its cluster's MLS query.
    Eigen::VectorXd spacing;
    SupportNeighbours rows = support_neighbours(q_index, kk + near_query_extra, 6, &spacing);
    const Eigen::VectorXd h = options.kernel * spacing;

    MlsResult projected;
    {
      MlsOptions mls = options.mls;
      mls.order = &groups.members;
      mls.near_support = &clusters.labels;
      mls.near_rows = &rows;
      if (sheets) { mls.point_sides = &sides; mls.support_sides = &cluster_sides; }
      projected = mls_project(fine, q_index, h, mls, stage.sub(0.1, 0.8));
    }
    rows = SupportNeighbours();

    // The level's own support: clusters, their neighbourhoods and kernels.
    LevelSupport& support = model.support[l - 1];
    support.labels = std::move(clusters.labels);
    support.clusters = static_cast<Index>(clusters.centroids.rows());
    support.neighbors = std::min<int>(kk, support.clusters);
    support.h = h;
    choose_anchors(fine, projected.positions, support, original.data());
    Points anchor_reference(support.clusters, 3);
    for (Index c = 0; c < support.clusters; ++c) anchor_reference.row(c) = projected.normals.row(support.anchors[c]);
    projected.normals = Points();  // before the frames' local coordinates take as much
    const Points centroids = support_centroids(projected.positions, support);
    support.neighborhoods = sheets ? same_side_knn_graph(SpatialIndex(centroids), cluster_sides, support.neighbors)
                                   : knn_graph(SpatialIndex(centroids), support.neighbors);
    // The same grouping (each cluster's points in input order) lays out the frames' coordinates:
    // in the input's numbering that is the layout of level_support.h.
    attach_frames(centroids, projected.positions, support, &groups);

    Points coarse = std::move(projected.positions);
    Points normals;
    const Consistency consistency = make_offsets_normal(fine, coarse, support, groups, anchor_reference, scale,
                                                        options.consistency_iterations, stage.sub(0.8, 1.0),
                                                        model.details.row(l - 1), normals);
    groups = LabelGroups();
    // How this level's normals turn against the finer level's: all that orienting the finer
    // one needs once this one is oriented, so a level's normals are not held, nor computed
    // again, after the next step.
    if (step > 0) turns[l] = turn_signs(finer_normals, finer_anchors, model.support[l], normals, original);
    finer_anchors = support_centroids(coarse, support);
    if (l == 1) normals0 = std::move(normals);
    else finer_normals = normals.cast<float>();
    fine = std::move(coarse);
    LevelReport& report = model.reports[l - 1];
    report.support_points = static_cast<std::size_t>(support.clusters);
    report.kernel_width = median(h);
    report.not_converged = projected.not_converged;
    report.degenerate = projected.degenerate;
    report.consistency_iterations = consistency.iterations;
    report.consistency_residual = consistency.residual;
    report.pinned = consistency.pinned;
  }

  release_free_memory();  // the last step's temporaries: the model is nearly all that is left
  // Orientation: level 0 from the input normals, or by propagation over the level-0 clusters;
  // every finer level agrees with the level below it at the same point (as reconstruction does).
  const ProgressStage last = all.sub(k / (k + 0.2), 1.0);
  const LevelSupport& s0 = model.support[0];
  // Point i's reference: its input normal, or its level-0 cluster's propagated normal.
  Points cluster_normals;
  if (!input_normals) {
    const Points& c0 = finer_anchors;
    std::vector<Index> own(static_cast<std::size_t>(s0.clusters));
    for (Index c = 0; c < s0.clusters; ++c) own[c] = c;
    cluster_normals = support_normals(c0, own.data(), c0, s0, Points::Zero(s0.clusters, 3));
    orient_normals(SpatialIndex(c0), cluster_normals, std::min<int>(16, s0.clusters));
  }
  auto reference0 = [&](Eigen::Index i) -> Vec3 {
    if (input_normals) return input_normals->row(original[static_cast<std::size_t>(i)]).transpose();
    return cluster_normals.row(s0.labels[i]).transpose();
  };
  last.report(0.5);
  // Orient each level's normals like support_normals does with a reference (flip where
  // n . reference < 0), and flip the details with them, so detail x normal is unchanged. Level
  // 0's normals are the ones built last; each finer level flips where its turn against the
  // oriented level below is negative, which is the sign of n_l . n_{l-1} (negating a vector
  // negates a dot product exactly, so this is the very test reconstruction makes).
  finer_normals.resize(0, 3);
  std::vector<unsigned char> flipped(static_cast<std::size_t>(n));
  for (Eigen::Index i = 0; i < n; ++i) {
    flipped[i] = normals0.row(i).dot(reference0(i).transpose()) < 0.0;
    if (flipped[i]) { normals0.row(i) = -normals0.row(i); model.details(0, i) = -model.details(0, i); }
  }
  model.base_normals = std::move(normals0);
  for (int l = 1; l < k; ++l) {
    for (Eigen::Index i = 0; i < n; ++i) {
      const int turn = turns[l][i];
      flipped[i] = flipped[i] ? turn > 0 : turn < 0;
      if (flipped[i]) model.details(l, i) = -model.details(l, i);
    }
    std::vector<signed char>().swap(turns[l]);
  }
  model.base = std::move(fine);
  // The model is complete: release what else is held before its arrays are copied to the
  // input's numbering, one at a time.
  std::vector<unsigned char>().swap(flipped);
  release_free_memory();
  renumber_model(model, original);
  last.report(1.0);
  return model;
}

}  // namespace pointscale
