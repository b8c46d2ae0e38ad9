// decompose's orientation, done once: while the levels are built top-down, each level's
// unoriented normals are kept only until the next level is built, as the sign of how they turn
// against its normals at each point; once level 0 is oriented, those signs orient every level.
#pragma once
#include <utility>
#include <vector>

#include "pointscale/detail/level_normals.h"

namespace pointscale {

class LevelTurns {
 public:
  explicit LevelTurns(int bands) : turns_(static_cast<std::size_t>(bands)), bands_(bands) {}

  // Level l-1 is built: its points (level), its unoriented normals and, in support[l-1], its
  // support; support[l] is the finer level's. original: the points' input numbers
  // (cluster_layout.h), by which the finer support's frames list each cluster's points.
  void add(int l, const Points& level, Points normals, const std::vector<LevelSupport>& support,
           const IndexList& original);

  // The anchors of the level added last (level 0 once all are added).
  const Points& last_anchors() const { return finer_anchors_; }

  // Orients level 0's normals like reference0(i) (a Vec3 per point; flip where n . reference
  // < 0), and each finer level where its turn against the oriented level below is negative,
  // which is the sign of n_l . n_{l-1} (negating a vector negates a dot product exactly, so this
  // is the very test reconstruction makes). Each flip negates the point's detail in that band
  // (details k by #P), so detail x normal is unchanged. Returns level 0's oriented normals.
  template <class Reference>
  Points orient(Eigen::MatrixXd& details, const Reference& reference0);

 private:
  using FloatNormals = Eigen::Matrix<float, Eigen::Dynamic, 3, Eigen::RowMajor>;
  FloatNormals finer_normals_;  // the level built last, in single precision (not level 0)
  Points finer_anchors_;        // its anchors
  Points normals0_;             // level 0's unoriented normals
  std::vector<std::vector<signed char>> turns_;  // turns_[l]: sign of n_l . n_{l-1} per point
  int bands_;
};

template <class Reference>
Points LevelTurns::orient(Eigen::MatrixXd& details, const Reference& reference0) {
  const Eigen::Index n = details.cols();
  finer_normals_.resize(0, 3);
  std::vector<unsigned char> flipped(static_cast<std::size_t>(n));
  for (Eigen::Index i = 0; i < n; ++i) {
    flipped[i] = normals0_.row(i).dot(reference0(i).transpose()) < 0.0;
    if (flipped[i]) { normals0_.row(i) = -normals0_.row(i); details(0, i) = -details(0, i); }
  }
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
