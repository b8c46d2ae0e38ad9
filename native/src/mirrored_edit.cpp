#include "pointscale/detail/mirrored_edit.h"

#include <Eigen/Eigenvalues>
#include <Eigen/LU>
#include <Eigen/SVD>
#include <algorithm>
#include <cmath>

#include "pointscale/parallel.h"
#include "pointscale/detail/level_normals.h"

namespace pointscale {

namespace {

// A part's votes, and sums over its anchors for a part too flat to vote.
struct PartTally {
  std::size_t clusters = 0, decided = 0, against = 0, alone = 0;
  Vec3 original = Vec3::Zero(), edited = Vec3::Zero();
  Mat3 cross = Mat3::Zero();   // sum (o - o_mean)(e - e_mean)^T over the anchors
  Mat3 spread = Mat3::Zero();  // sum (o - o_mean)(o - o_mean)^T over the anchors
  double spread_original = 0.0, spread_edited = 0.0;
};

// A part whose clusters mostly cannot tell (a nearly flat one: a plate, a relief, a terrain; or
// one with a handful of clusters, each neighbourhood holding most of the part), judged from its
// anchors as a whole. Its best linear map A (least squares about the centroids) must reverse
// orientation. The nearest orthogonal map to A is then a mirror across some plane, perhaps with
// a turn about that plane's normal v (v: its eigenvector of eigenvalue -1):
//  - where the part spreads along v (at least 5% of its largest spread), the mirror cuts across
//    it, as no half turn does: mirrored when A explains the edit to 1% of the edited spread (a
//    mirror with a brush, a smoothing or a scale of -1.02 on top) and crushes no direction (its
//    singular values within a factor of 20);
//  - where v is the part's thin direction, the map mirrors the part across its own plane, as a
//    half turn or a dimple pressed through it moves it too: mirrored only when the anchors are a
//    mirror to within rounding. With the singular values s1 >= s2 >= s3 of the cross sums, a
//    mirror-similarity and a similarity fit to within E - (s1 + s2 + s3)^2 / O and
//    E - (s1 + s2 - s3)^2 / O: the first must be below 1e-6 of E, the second four times above it.
// A flat part (spread of rank 2) has no orientation at all.
bool mirrored_as_a_whole(const PartTally& t) {
  if (t.clusters < 4 || !(t.spread_original > 0.0) || !(t.cross.determinant() < 0.0)) return false;
  const Eigen::SelfAdjointEigenSolver<Mat3> shape(t.spread);
  const Vec3 ev = shape.eigenvalues();  // ascending
  if (!(ev(0) > 1e-9 * ev(2))) return false;
  const Mat3 map = t.cross.transpose() * t.spread.inverse();  // e - e_mean = map (o - o_mean)
  const Eigen::JacobiSVD<Mat3> polar(map, Eigen::ComputeFullU | Eigen::ComputeFullV);
  // A map that crushes a direction (a part squashed flat, or noise on a nearly flat part, whose
  // thin direction's fit it blows up) has no orientation to read.
  if (!(polar.singularValues()(2) >= 0.05 * polar.singularValues()(0))) return false;
  const Mat3 nearest = polar.matrixU() * polar.matrixV().transpose();  // orthogonal, determinant -1
  const Eigen::JacobiSVD<Mat3> fixed(nearest + Mat3::Identity(), Eigen::ComputeFullV);
  const Vec3 normal = fixed.matrixV().col(2);  // (nearest + I) v = 0: the mirror's normal
  if (normal.dot(t.spread * normal) >= 0.05 * ev(2)) {
    const double unexplained = t.spread_edited - (t.cross.transpose() * t.spread.inverse() * t.cross).trace();
    return unexplained < 1e-2 * t.spread_edited;
  }
  const Eigen::JacobiSVD<Mat3> svd(t.cross);
  const Vec3 sv = svd.singularValues();
  const double mirror = sv(0) + sv(1) + sv(2), turn = sv(0) + sv(1) - sv(2);
  const double misfit_mirror = t.spread_edited - mirror * mirror / t.spread_original;
  const double misfit_turn = t.spread_edited - turn * turn / t.spread_original;
  return misfit_mirror <= 1e-6 * t.spread_edited && misfit_turn > 4.0 * std::max(misfit_mirror, 1e-9 * t.spread_edited);
}

}  // namespace

std::vector<unsigned char> mirrored_points(const Points& original, const Points& edited, const LevelSupport& level0,
                                           const IndexList& parts, const std::vector<signed char>& vote) {
  const Points b0 = support_centroids(original, level0);
  const Points b1 = support_centroids(edited, level0);
  // Each part's tally, by its clusters' anchors, in cluster order (the same in any point order).
  Index labels = 1;
  for (Index p : parts) labels = std::max(labels, p + 1);
  std::vector<PartTally> tally(static_cast<std::size_t>(labels));
  auto part_of = [&](std::size_t c) {
    return parts.empty() ? std::size_t(0) : static_cast<std::size_t>(parts[static_cast<std::size_t>(level0.anchors[c])]);
  };
  for (std::size_t c = 0; c < vote.size(); ++c) {
    PartTally& t = tally[part_of(c)];
    ++t.clusters;
    t.original += b0.row(static_cast<Eigen::Index>(c)).transpose();
    t.edited += b1.row(static_cast<Eigen::Index>(c)).transpose();
    if (vote[c] == 2) ++t.alone;
    if (vote[c] != 1 && vote[c] != -1) continue;
    ++t.decided;
    if (vote[c] < 0) ++t.against;
  }
  for (PartTally& t : tally)
    if (t.clusters > 0) { t.original /= static_cast<double>(t.clusters); t.edited /= static_cast<double>(t.clusters); }
  for (std::size_t c = 0; c < vote.size(); ++c) {
    PartTally& t = tally[part_of(c)];
    const Vec3 o = b0.row(static_cast<Eigen::Index>(c)).transpose() - t.original;
    const Vec3 e = b1.row(static_cast<Eigen::Index>(c)).transpose() - t.edited;
    t.cross.noalias() += o * e.transpose();
    t.spread.noalias() += o * o.transpose();
    t.spread_original += o.squaredNorm();
    t.spread_edited += e.squaredNorm();
  }
  // A mirror moves every cluster of the part and reverses every one that can tell. A part
  // votes where its clusters' neighbourhoods are local (the part has at least three times as
  // many clusters as a neighbourhood holds) and a quarter of them can tell: mirrored when nine
  // in ten of those say reversed and the edit left at most one in twenty of all its clusters
  // alone. So a dent that presses a cap through a plane, even most of the part, is not a mirror
  // of the part: the rest stays as it was, or turns as a bend does. Otherwise (a nearly flat
  // part, or one with a handful of clusters, each neighbourhood holding most of the part) it is
  // judged as a whole.
  std::vector<unsigned char> part_mirrored(tally.size(), 0);
  bool any = false;
  const std::size_t local = 3 * static_cast<std::size_t>(std::max(level0.neighbors, 1));
  for (std::size_t p = 0; p < tally.size(); ++p) {
    const PartTally& t = tally[p];
    const bool votes = t.clusters >= local && t.decided >= 4 && 4 * t.decided >= t.clusters;
    const bool moved = 20 * t.alone <= t.clusters;
    part_mirrored[p] = moved && (votes ? 10 * t.against >= 9 * t.decided : mirrored_as_a_whole(t));
    any |= part_mirrored[p] != 0;
  }
  if (!any) return {};
  // A mirror moves every point of the part but those on its plane. A part whose points were left
  // where they were, more than one in twenty, was pressed through a plane in part (a dent), not
  // mirrored, however its anchors look: a handful of anchors can all lie in the pressed cap.
  std::vector<std::size_t> points(tally.size(), 0), still(tally.size(), 0);
  for (Eigen::Index i = 0; i < original.rows(); ++i) {
    const std::size_t p = parts.empty() ? 0 : static_cast<std::size_t>(parts[static_cast<std::size_t>(i)]);
    if (!part_mirrored[p]) continue;
    ++points[p];
    if (original.row(i) == edited.row(i)) ++still[p];
  }
  any = false;
  for (std::size_t p = 0; p < tally.size(); ++p) {
    if (part_mirrored[p] && 20 * still[p] > points[p]) part_mirrored[p] = 0;
    any |= part_mirrored[p] != 0;
  }
  if (!any) return {};
  std::vector<unsigned char> flags(static_cast<std::size_t>(original.rows()));
  for (std::size_t i = 0; i < flags.size(); ++i) flags[i] = part_mirrored[parts.empty() ? 0 : static_cast<std::size_t>(parts[i])];
  return flags;
}

void reflect_rows(Points& p, const std::vector<unsigned char>& flags) {
  if (flags.empty()) return;
  parallel_for(flags.size(), [&](std::size_t b, std::size_t e) {
    for (std::size_t i = b; i < e; ++i)
      if (flags[i]) p(static_cast<Eigen::Index>(i), 0) = -p(static_cast<Eigen::Index>(i), 0);
  }, {}, 16384);
}

}  // namespace pointscale
