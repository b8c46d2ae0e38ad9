#include "pointscale/detail/mirrored_edit.h"
#include "pointscale/mirrored_parts.h"

#include <Eigen/LU>
#include <Eigen/SVD>
#include <algorithm>
#include <stdexcept>

#include "pointscale/parallel.h"
#include "pointscale/detail/level_normals.h"
#include "pointscale/detail/transported_rotations.h"

namespace pointscale {

namespace {

// A part's orientation votes at one level (transported_rotations.h: 1 kept, -1 reversed, 0 cannot
// tell, 2 left alone).
struct VoteCount {
  std::size_t clusters = 0, decided = 0, against = 0, alone = 0;
  void add(signed char vote) {
    ++clusters;
    if (vote == 2) ++alone;
    if (vote != 1 && vote != -1) return;
    ++decided;
    if (vote < 0) ++against;
  }
  // Whether they say mirrored: a mirror moves every cluster and reverses every one that can
  // tell. Enough clusters must tell (4, and a quarter of them); then nine in ten of those must
  // say reversed, and at most one in twenty of all be left alone. So a dent that presses a cap
  // through a plane, even most of the part, is no mirror of it: the rest stays, or turns as a
  // bend does. 1 mirrored, 0 not, -1 cannot tell.
  int verdict() const {
    if (decided < 4 || 4 * decided < clusters) return -1;
    return 10 * against >= 9 * decided && 20 * alone <= clusters ? 1 : 0;
  }
};

// A part's level-0 votes, and sums over its anchors for a part too flat to vote.
struct PartTally {
  VoteCount votes;
  Vec3 original = Vec3::Zero(), edited = Vec3::Zero();
  Mat3 cross = Mat3::Zero();  // sum (o - o_mean)(e - e_mean)^T over the anchors
  double spread_original = 0.0, spread_edited = 0.0;
};

// A part whose clusters cannot tell at any level (a nearly flat part: a plate, a relief, a
// terrain; or one too small for local neighbourhoods), judged from its level-0 anchors as a
// whole: mirrored only when they are a mirror of the stored ones to within rounding. A mirror
// across the part's own plane looks like a half turn or a dimple pressed through it, and on a
// nearly flat part the fit of its thin direction follows any warp: only a mirror alone is told
// apart. With the singular values s1 >= s2 >= s3 of the cross sums, where the best orthogonal
// map reverses orientation, a mirror-similarity and a similarity fit to within
// E - (s1 + s2 + s3)^2 / O and E - (s1 + s2 - s3)^2 / O: the first must be below 1e-6 of E and
// the second four times above it. A flat part (s3 = 0) has no orientation at all.
bool mirrored_as_a_whole(const PartTally& t) {
  if (t.votes.clusters < 4 || !(t.spread_original > 0.0) || !(t.cross.determinant() < 0.0)) return false;
  const Eigen::JacobiSVD<Mat3> svd(t.cross);
  const Vec3 sv = svd.singularValues();
  if (!(sv(2) > 1e-9 * sv(0))) return false;
  const double mirror = sv(0) + sv(1) + sv(2), turn = sv(0) + sv(1) - sv(2);
  const double misfit_mirror = t.spread_edited - mirror * mirror / t.spread_original;
  const double misfit_turn = t.spread_edited - turn * turn / t.spread_original;
  return misfit_mirror <= 1e-6 * t.spread_edited && misfit_turn > 4.0 * std::max(misfit_mirror, 1e-9 * t.spread_edited);
}

// Cluster c's orientation vote at a level (transported_rotations.h: 1 kept, -1 reversed, 0 cannot
// tell, 2 left alone), from the base positions of the level's anchors.
signed char cluster_vote(const Points& b0, const Points& b1, const LevelSupport& support, Index c) {
  Mat3 cov;
  if (!neighbourhood_cross(b0, b1, support, c, cov)) return 2;
  return orientation_vote(Eigen::JacobiSVD<Mat3>(cov, Eigen::ComputeFullU | Eigen::ComputeFullV));
}

}  // namespace

std::vector<unsigned char> mirrored_points(const Points& original, const Points& edited,
                                           const std::vector<LevelSupport>& support, const IndexList& parts,
                                           const std::vector<signed char>& vote) {
  const LevelSupport& level0 = support.front();
  const Points b0 = support_centroids(original, level0);
  const Points b1 = support_centroids(edited, level0);
  // Each part's tally, by its clusters' anchors, in cluster order (the same in any point order).
  Index labels = 1;
  for (Index p : parts) labels = std::max(labels, p + 1);
  std::vector<PartTally> tally(static_cast<std::size_t>(labels));
  auto part_of_point = [&](Index i) { return parts.empty() ? std::size_t(0) : static_cast<std::size_t>(parts[static_cast<std::size_t>(i)]); };
  for (std::size_t c = 0; c < vote.size(); ++c) {
    PartTally& t = tally[part_of_point(level0.anchors[c])];
    t.votes.add(vote[c]);
    t.original += b0.row(static_cast<Eigen::Index>(c)).transpose();
    t.edited += b1.row(static_cast<Eigen::Index>(c)).transpose();
  }
  for (PartTally& t : tally) {
    const double count = static_cast<double>(t.votes.clusters);
    if (count > 0) { t.original /= count; t.edited /= count; }
  }
  for (std::size_t c = 0; c < vote.size(); ++c) {
    PartTally& t = tally[part_of_point(level0.anchors[c])];
    const Vec3 o = b0.row(static_cast<Eigen::Index>(c)).transpose() - t.original;
    const Vec3 e = b1.row(static_cast<Eigen::Index>(c)).transpose() - t.edited;
    t.cross.noalias() += o * e.transpose();
    t.spread_original += o.squaredNorm();
    t.spread_edited += e.squaredNorm();
  }
  // Votes count where neighbourhoods are local: the part has at least ten times as many
  // clusters as a neighbourhood holds. A part with fewer at level 0 is a candidate when its
  // level-0 votes, though not local, say reversed as a mirror's do (nine in ten of those that
  // tell) and its anchors' best orthogonal map reverses: it then votes at the first finer level
  // where it has that many clusters, from the base positions of that level's anchors. Other
  // parts cost nothing more on each call, also through an editing session on a dented part. A
  // part whose clusters cannot tell (nearly flat) is judged as a whole.
  std::vector<int> verdict(tally.size(), 0);
  std::vector<unsigned char> pending(tally.size(), 0);
  bool any = false, waiting = false;
  const auto local = [&](const LevelSupport& s) { return 10 * static_cast<std::size_t>(std::max(s.neighbors, 1)); };
  for (std::size_t p = 0; p < tally.size(); ++p) {
    const PartTally& t = tally[p];
    const VoteCount& v = t.votes;
    const bool is_local = v.clusters >= local(level0);
    verdict[p] = is_local ? v.verdict() : -1;
    if (!is_local && v.decided > 0) {
      verdict[p] = 0;  // it can tell: the finer votes decide, or it is no mirror
      if (10 * v.against >= 9 * v.decided && t.cross.determinant() < 0.0) { pending[p] = 1; waiting = true; }
    }
  }
  for (std::size_t l = 1; waiting && l < support.size(); ++l) {
    const LevelSupport& s = support[l];
    std::vector<std::size_t> clusters(tally.size(), 0);
    for (Index a : s.anchors) ++clusters[part_of_point(a)];
    std::vector<Index> voting;  // the clusters of pending parts local enough here
    for (std::size_t c = 0; c < s.anchors.size(); ++c) {
      const std::size_t p = part_of_point(s.anchors[c]);
      if (pending[p] && clusters[p] >= local(s)) voting.push_back(static_cast<Index>(c));
    }
    if (voting.empty()) continue;
    const Points c0 = support_centroids(original, s), c1 = support_centroids(edited, s);
    std::vector<signed char> votes(voting.size());
    parallel_for(voting.size(), [&](std::size_t b, std::size_t e) {
      for (std::size_t j = b; j < e; ++j) votes[j] = cluster_vote(c0, c1, s, voting[j]);
    }, {}, 256);
    std::vector<VoteCount> count(tally.size());  // every cluster of a voting part votes
    for (std::size_t j = 0; j < voting.size(); ++j)
      count[part_of_point(s.anchors[static_cast<std::size_t>(voting[j])])].add(votes[j]);
    waiting = false;
    for (std::size_t p = 0; p < tally.size(); ++p) {
      if (!pending[p] || clusters[p] < local(s)) { waiting |= pending[p] != 0; continue; }
      verdict[p] = count[p].verdict();
      pending[p] = 0;  // local here: this level's votes, or a whole judgement, decide
    }
  }
  std::vector<unsigned char> part_mirrored(tally.size(), 0);
  for (std::size_t p = 0; p < tally.size(); ++p) {
    if (pending[p]) verdict[p] = -1;  // no level local enough: judged as a whole
    part_mirrored[p] = verdict[p] > 0 || (verdict[p] < 0 && mirrored_as_a_whole(tally[p]));
    any |= part_mirrored[p] != 0;
  }
  if (!any) return {};
  std::vector<unsigned char> flags(static_cast<std::size_t>(original.rows()));
  for (std::size_t i = 0; i < flags.size(); ++i) flags[i] = part_mirrored[part_of_point(static_cast<Index>(i))];
  return flags;
}

std::vector<unsigned char> mirrored_parts(const MultiscaleModel& model, const Points& edited) {
  if (edited.rows() != model.base.rows() || model.bands() == 0)
    throw std::invalid_argument("edited must be the model's (n, 3) base, and the model must have bands");
  std::vector<signed char> votes;
  transported_rotations(model.base, edited, model.support[0], &votes);
  std::vector<unsigned char> flags = mirrored_points(model.base, edited, model.support, model.parts, votes);
  flags.resize(static_cast<std::size_t>(edited.rows()), 0);
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
