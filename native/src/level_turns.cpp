#include "pointscale/detail/level_turns.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include "pointscale/parallel.h"
#include "pointscale/detail/level_normals.h"
#include "pointscale/detail/level_orientation.h"

namespace pointscale {

namespace {

using FloatNormals = Eigen::Matrix<float, Eigen::Dynamic, 3, Eigen::RowMajor>;

// Per point, the sign of n_finer . n (-1, 0 or 1): the finer level's normals, held in single
// precision, against the unoriented normals of the level below it. Single precision tells the
// sign wherever the dot product is not near 0; there the finer level's normals are evaluated
// again, exactly, for the clusters concerned (anchor_normals_of_clusters: bitwise as before).
// finer_anchors #C by 3 and finer: the finer level's anchors and support.
// original: the points' input numbers, by which finer.local lists each cluster's points.
std::vector<signed char> turn_signs(const FloatNormals& finer_normals, const Points& finer_anchors,
                                    const LevelSupport& finer, const Points& normals, const IndexList& original,
                                    std::vector<float>* sureness) {
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
      if (sureness) (*sureness)[ii] = std::min((*sureness)[ii], static_cast<float>(std::abs(d)));
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

}  // namespace

void LevelTurns::add(int l, const Points& level, Points normals, const std::vector<LevelSupport>& support,
                     const IndexList& original, Points* cluster_normals) {
  if (orient_finest_ && l == bands_) sureness_.assign(static_cast<std::size_t>(level.rows()), 1.0f);
  if (l < bands_)
    turns_[l] = turn_signs(finer_normals_, finer_anchors_, support[l], normals, original,
                           orient_finest_ ? &sureness_ : nullptr);
  finer_anchors_ = support_centroids(level, support[l - 1]);
  if (orient_finest_ && l == bands_) {
    const LevelSupport& finest = support[l - 1];
    if (!cluster_normals) throw std::logic_error("LevelTurns: the finest level needs its clusters' normals");
    Points& reference = *cluster_normals;
    orient_cluster_normals(finer_anchors_, reference, finest);
    finest_flipped_.resize(static_cast<std::size_t>(level.rows()));
    parallel_for(finest_flipped_.size(), [&](std::size_t b, std::size_t e) {
      for (std::size_t i = b; i < e; ++i) {
        const auto row = static_cast<Eigen::Index>(i);
        finest_flipped_[i] = normals.row(row).dot(reference.row(finest.labels[i])) < 0.0;
      }
    }, {}, 4096);
  }
  if (l == 1) normals0_ = std::move(normals);
  else finer_normals_ = normals.cast<float>();
}

std::vector<unsigned char> LevelTurns::level0_flips_from_finest() const {
  if (finest_flipped_.size() != static_cast<std::size_t>(normals0_.rows()))
    throw std::logic_error("LevelTurns: the finest level was not oriented");
  // Down from the finest level: level l-1 is flipped where level l is, unless they turn
  // against each other there (a turn of 0, a right angle exactly, is taken as no turn).
  std::vector<unsigned char> flipped = finest_flipped_;
  for (int l = bands_ - 1; l >= 1; --l)
    for (std::size_t i = 0; i < flipped.size(); ++i)
      if (turns_[l][i] < 0) flipped[i] = !flipped[i];
  return flipped;
}

Points LevelTurns::orient_upward(Eigen::MatrixXd& details, std::vector<unsigned char>& flipped) {
  const Eigen::Index n = details.cols();
  finer_normals_.resize(0, 3);
  for (Eigen::Index i = 0; i < n; ++i)
    if (flipped[i]) { normals0_.row(i) = -normals0_.row(i); details(0, i) = -details(0, i); }
  Points base_normals = std::move(normals0_);
  for (int l = 1; l < bands_; ++l) {
    for (Eigen::Index i = 0; i < n; ++i) {
      const int turn = turns_[l][i];
      flipped[i] = flipped[i] ? turn > 0 : turn < 0;
      if (flipped[i]) details(l, i) = -details(l, i);
    }
    std::vector<signed char>().swap(turns_[l]);
  }
  return base_normals;
}

}  // namespace pointscale
