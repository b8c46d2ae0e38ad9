#include "pointscale/detail/align_offsets.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <vector>

#include "pointscale/parallel.h"
#include "pointscale/detail/plane_fit.h"
#include "pointscale/detail/offset_alignment.h"
#include "pointscale/detail/level_normals.h"

namespace pointscale {

namespace {

// A move more than a tenth above the last halves the step, down to 1/1024; a smaller move lets
// it grow back by a quarter, up to the anchor's Newton step.
constexpr DampingPolicy encode_damping{1.1, 1.0 / 1024.0, 1.25, false};

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
        const Vec3 target = tangent_foot(f, p, nrm);
        const Vec3 move = target - p;
        const double full = move.norm();
        // A growing move means the step is too long: halve it. A shrinking one lets it grow back
        // towards the Newton step, so that noise in the neighbours' moves cannot stall an anchor.
        damping[c] = next_damping(encode_damping, damping[c], full, moves[c], newton[c]);
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
  std::vector<unsigned char> stays(static_cast<std::size_t>(level.rows()), 0);
  std::vector<double> left(static_cast<std::size_t>(level.rows()), 0.0);
  step_non_anchors(
      fine, level, normals, support,
      [&](Eigen::Index i, const Vec3& target, const Vec3& nrm) {
        const std::size_t ii = static_cast<std::size_t>(i);
        if ((target - start.row(i).transpose()).norm() <= reach(i, support.labels[ii]))
          level.row(i) = settle(target, nrm).transpose();
        else stays[ii] = 1;
      },
      [&](Eigen::Index i, const Vec3& f, const Vec3& nrm) {
        const Vec3 d = f - level.row(i).transpose();
        left[static_cast<std::size_t>(i)] = (d - d.dot(nrm) * nrm).norm();
      });
  for (Index c = 0; c < c_count; ++c) out.kept += kept[c];
  for (unsigned char s : stays) out.kept += s;
  out.residual = *std::max_element(left.begin(), left.end());
  stage.report(1.0);
  return out;
}

}  // namespace pointscale
