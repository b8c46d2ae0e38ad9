#include "pointscale/decomposition.h"
#include "pointscale/validation.h"

#include <algorithm>
#include <cmath>
#include <utility>

#include "pointscale/cluster_decimation.h"
#include "pointscale/detail/release_memory.h"
#include "pointscale/detail/renumber_points.h"
#include "pointscale/spatial_index.h"
#include "pointscale/detail/support_neighbours.h"
#include "pointscale/detail/thin_sheets.h"
#include "pointscale/detail/build_level_support.h"
#include "pointscale/detail/cluster_layout.h"
#include "pointscale/detail/coincident_points.h"
#include "pointscale/detail/level_orientation.h"
#include "pointscale/detail/level_turns.h"
#include "pointscale/detail/make_offsets_normal.h"
#include "pointscale/detail/mls_hints.h"
#include "pointscale/detail/level_normals.h"

// decompose builds the levels top-down, P^k = P, then P^{k-1}, ..., P^0; each step is
//   decimate_level   P^l -> Q^{l-1}, its clusters (Sec. 5.2)
//   project_level    P^l onto the MLS surface of Q^{l-1} (Sec. 2)
//   build_support    the level's support: anchors, neighbourhoods, kernels, frames
//   make_offsets_normal  P^l - P^{l-1} exactly along the recomputed normals (Sec. 7)
//   LevelTurns::add  how the level's normals turn against the finer level's
// and once level 0 is known, orient_levels orients every level's normals and details.
// From the first decimation on the points are numbered in the layout of cluster_layout.h;
// renumber_model numbers the finished model back.

namespace pointscale {

namespace {

double median(Eigen::VectorXd v) {
  if (v.size() == 0) return 0.0;
  std::nth_element(v.data(), v.data() + v.size() / 2, v.data() + v.size());
  return v(v.size() / 2);
}

// Thin sheets: each point's oriented input normal tells the side of a wall it is on, at every
// level (smoothing moves a point along its surface, never through the wall).
struct Sheets {
  bool on = false;
  const Points* input_normals = nullptr;  // #P by 3, in the input's numbering
  Points* owned = nullptr;                // the same when handed over: released once renumbered
  Points sides;                           // #P by 3, the same in the points' current numbering
};

// Q^{l-1}, and P^l grouped by it.
struct Decimation {
  Clustering clusters;   // centroids #C by 3 (diffused when asked), labels #P
  LabelGroups groups;    // P^l in the layout of cluster_layout.h
  Points cluster_sides;  // #C by 3 with thin sheets, else empty
};

// Decimates P^l (fine) to `target` clusters. The first step renumbers the points (and their
// sides) in its layout: original[i] is then point i's input number.
Decimation decimate_level(Points& fine, std::size_t target, const DecomposeOptions& options, bool first,
                          IndexList& original, Sheets& sheets) {
  IndexList input_order;  // the points' current numbers in the input's order
  if (!original.empty()) input_order = inverse_order(original);
  const Points* side_normals = !sheets.on ? nullptr : original.empty() ? sheets.input_normals : &sheets.sides;
  Decimation out;
  out.clusters = cluster_decimate(fine, target, options.max_variation, original.empty() ? nullptr : &input_order,
                                  side_normals);
  const auto cluster_count = static_cast<Index>(out.clusters.centroids.rows());
  out.groups = cluster_layout(out.clusters.labels, cluster_count, original.empty() ? nullptr : input_order.data());
  input_order = IndexList();
  if (first) {
    original = number_by_groups(fine, out.clusters.labels, out.groups);
    if (sheets.on) sheets.sides = gather_rows(*sheets.input_normals, original);
    // sides holds them from here on: the decimation and level 0's orientation read only sides.
    if (sheets.on && sheets.owned) Points().swap(*sheets.owned);
    release_free_memory();  // the input's copy in its own numbering
  }
  if (sheets.on) out.cluster_sides = cluster_side_normals(sheets.sides, out.clusters.labels, cluster_count);
  if (options.diffusion) out.clusters.centroids = diffuse(out.clusters.centroids, *options.diffusion);
  return out;
}

// P^l projected onto the MLS surface of Q^{l-1}.
struct Projection {
  MlsResult projected;
  Eigen::VectorXd h;  // #C kernel widths: kernel x the local spacing of Q^{l-1}
};

// Cluster by cluster, each cluster's points around one query at its centroid, in the layout's
// order. Each centroid's nearest centroids are asked once: its kernel width and its cluster's
// MLS query.
Projection project_level(const Points& fine, const Decimation& decimated, const DecomposeOptions& options,
                         const Sheets& sheets, const ProgressStage& stage) {
  const SpatialIndex q_index(decimated.clusters.centroids);
  Eigen::VectorXd spacing;
  const SupportNeighbours rows = support_neighbours(q_index, options.mls.neighbors + near_query_extra, 6, &spacing);
  Projection out;
  out.h = options.kernel * spacing;
  MlsOptions mls = options.mls;
  mls.order = &decimated.groups.members;
  mls.near_support = &decimated.clusters.labels;
  MlsHints hints;
  hints.near_rows = &rows;
  if (sheets.on) { hints.point_sides = &sheets.sides; hints.support_sides = &decimated.cluster_sides; }
  out.projected = mls_project(fine, q_index, out.h, mls, hints, stage);
  return out;
}

// The level's support from its clusters and projected points; returns the anchors' projected
// normals (#C by 3), which orient them while their offsets are made normal. The projection's
// normals are released before the frames' local coordinates take as much.
Points build_support(const Points& fine, Projection& projection, Decimation& decimated, const IndexList& original,
                     const DecomposeOptions& options, bool sheets, LevelSupport& support) {
  const auto cluster_count = static_cast<Index>(decimated.clusters.centroids.rows());
  support = start_level_support(std::move(decimated.clusters.labels), cluster_count, options.mls.neighbors);
  choose_anchors(fine, projection.projected.positions, support, original.data());
  Points anchor_reference(support.clusters, 3);
  for (Index c = 0; c < support.clusters; ++c)
    anchor_reference.row(c) = projection.projected.normals.row(support.anchors[c]);
  projection.projected.normals = Points();
  LevelSupportRecipe recipe;
  recipe.h = &projection.h;
  recipe.cluster_sides = sheets ? &decimated.cluster_sides : nullptr;
  recipe.groups = &decimated.groups;
  finish_level_support(projection.projected.positions, support, recipe);
  return anchor_reference;
}

LevelReport level_report(const LevelSupport& support, const Projection& projection, const Consistency& consistency) {
  LevelReport report;
  report.support_points = static_cast<std::size_t>(support.clusters);
  report.kernel_width = median(projection.h);
  report.not_converged = projection.projected.not_converged;
  report.degenerate = projection.projected.degenerate;
  report.consistency_iterations = consistency.iterations;
  report.consistency_residual = consistency.residual;
  report.pinned = consistency.pinned;
  return report;
}

// Without input normals, level 0's clusters' normals (#C by 3), each oriented by a vote of its
// points: the side that, through the turns at each point, makes the finest level agree with
// its own propagated orientation (level_turns.h). Each point weighs by its agreement with the
// cluster's normal and by how sure its turns are: where two levels' normals are nearly at right
// angles (the walls of tall detail over a flat base) a turn's sign is a toss-up. Level 0's
// anchors are sparse: propagated over them alone, the orientation reached across thin parts
// and sharp creases and turned whole regions in. No propagation joins the clusters either:
// where a coarse base folds under a thin feature, level-0 normals made to agree with their
// neighbours turn that feature's finer detail in (on the bunny at 4 levels, joined along a
// spanning forest of the clusters, 6% of the finest normals faced in; voted apart, 3%).
Points level0_normals_from_finest(const LevelTurns& turns, const LevelSupport& s0) {
  Points anchor = anchor_normals(turns.last_anchors(), s0);
  const std::vector<unsigned char> flips = turns.level0_flips_from_finest();
  const std::vector<float>& sure = turns.turn_sureness();
  const Points& n0 = turns.level0_normals();
  // In point order: the same at any thread count.
  std::vector<double> vote(static_cast<std::size_t>(s0.clusters), 0.0);
  for (Eigen::Index i = 0; i < n0.rows(); ++i) {
    const Index c = s0.labels[i];
    const double agree = sure[i] * n0.row(i).dot(anchor.row(c));
    vote[c] += flips[i] ? -agree : agree;
  }
  for (Index c = 0; c < s0.clusters; ++c)
    if (vote[c] < 0.0) anchor.row(c) = -anchor.row(c);
  return anchor;
}

// Orients level 0 from the input normals, or by its clusters' normals oriented from the finest
// level (level0_normals_from_finest), then every finer level like the level below it at the
// same point (as reconstruction does), flipping the details with the normals so that detail x
// normal is unchanged.
// sides: with thin sheets, the input normals in the points' numbering (the same rows, exactly).
void orient_levels(MultiscaleModel& model, LevelTurns& turns, const Points* input_normals, const Points* sides,
                   const IndexList& original, const ProgressStage& stage) {
  const LevelSupport& s0 = model.support[0];
  // Point i's reference: its input normal, or its level-0 cluster's oriented normal.
  Points cluster_normals;
  if (!input_normals) cluster_normals = level0_normals_from_finest(turns, s0);
  auto reference0 = [&](Eigen::Index i) -> Vec3 {
    if (sides) return sides->row(i).transpose();
    if (input_normals) return input_normals->row(original[static_cast<std::size_t>(i)]).transpose();
    return cluster_normals.row(s0.labels[i]).transpose();
  };
  stage.report(0.5);
  model.base_normals = turns.orient(model.details, reference0);
}

// owned: input_normals itself when the caller handed them over, else nullptr.
MultiscaleModel decompose_levels(Points points, const Points* input_normals, Points* owned,
                                 const DecomposeOptions& options, const ProgressCallback* progress) {
  check_decompose_input(points, input_normals, options);
  const Eigen::Index n = points.rows();
  const int k = options.levels - 1;
  const double scale = (points.colwise().maxCoeff() - points.colwise().minCoeff()).norm();
  const ProgressStage all{progress, 0.0, 1.0};

  MultiscaleModel model;
  model.support.resize(k);
  model.reports.resize(k);
  // Only the level being built and the one it comes from are held; a finished level keeps its
  // detail along its unoriented normals, and how those turn against the next level's.
  Points fine = std::move(points);
  model.details.resize(k, n);
  LevelTurns turns(k, input_normals == nullptr);
  // Point i is input point original[i] from the first decimation on (cluster_layout.h).
  IndexList original;
  Sheets sheets;
  sheets.on = options.thin_sheets && input_normals && input_normals->rows() == n;
  sheets.input_normals = input_normals;
  sheets.owned = owned;

  // Input points that coincide, in the numbering from the first decimation on: each level's
  // projection gives them one place (coincident_points.h).
  std::vector<std::pair<Index, Index>> copies;
  for (int step = 0; step < k; ++step) {
    const int l = k - step;  // builds level l-1 from level l
    const ProgressStage stage = all.sub(static_cast<double>(step) / (k + 0.2), static_cast<double>(step + 1) / (k + 0.2));
    stage.report(0.0);
    // |Q^{l-1}| = gamma^(step+1) n (Sec. 5.2).
    const auto target = static_cast<std::size_t>(std::floor(std::pow(options.decimation, step + 1) * n));
    Decimation decimated = decimate_level(fine, target, options, step == 0, original, sheets);
    if (step == 0) copies = coincident_points(fine, decimated.groups, sheets.on ? &sheets.sides : nullptr);
    stage.report(0.05);
    Projection projection = project_level(fine, decimated, options, sheets, stage.sub(0.1, 0.8));
    unify_coincident(copies, projection.projected.positions, projection.projected.normals);
    LevelSupport& support = model.support[l - 1];
    Points anchor_reference = build_support(fine, projection, decimated, original, options, sheets.on, support);
    Points coarse = std::move(projection.projected.positions);
    Points normals;
    const Consistency consistency = make_offsets_normal(fine, coarse, support, decimated.groups, anchor_reference, scale,
                                                        options.consistency_iterations, stage.sub(0.8, 1.0),
                                                        model.details.row(l - 1), normals);
    unify_coincident(copies, support.anchors, coarse, normals, model.details.row(l - 1));
    decimated.groups = LabelGroups();
    turns.add(l, coarse, std::move(normals), model.support, original, step == 0 ? &anchor_reference : nullptr);
    fine = std::move(coarse);
    model.reports[l - 1] = level_report(support, projection, consistency);
  }

  release_free_memory();  // the last step's temporaries: the model is nearly all that is left
  const ProgressStage last = all.sub(k / (k + 0.2), 1.0);
  orient_levels(model, turns, input_normals, sheets.on ? &sheets.sides : nullptr, original, last);
  model.base = std::move(fine);
  // The model is complete: release what else is held before its arrays are copied to the
  // input's numbering, one at a time.
  turns = LevelTurns(0, false);
  release_free_memory();
  renumber_model(model, original);
  last.report(1.0);
  return model;
}

}  // namespace

MultiscaleModel decompose(Points points, const Points* input_normals, const DecomposeOptions& options,
                          const ProgressCallback* progress) {
  return decompose_levels(std::move(points), input_normals, nullptr, options, progress);
}

MultiscaleModel decompose(Points points, Points input_normals, const DecomposeOptions& options,
                          const ProgressCallback* progress) {
  return decompose_levels(std::move(points), &input_normals, &input_normals, options, progress);
}

}  // namespace pointscale
