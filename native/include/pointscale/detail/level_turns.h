// decompose's orientation, done once: while the levels are built top-down, each level's
// unoriented normals are kept only until the next level is built, as the sign of how they turn
// against its normals at each point; once level 0 is oriented, those signs orient every level.
// Without given normals, the orientation is propagated on the finest level, the first built:
// its anchors are the densest of the model, and a spanning tree over them crosses no thin part
// or sharp crease that level 0's sparse anchors (16 times fewer at the default decimation)
// reach across. The turns then carry it down to level 0 point by point.
#pragma once
#include <utility>
#include <vector>

#include "pointscale/detail/level_normals.h"

namespace pointscale {

class LevelTurns {
 public:
  // orient_finest: propagate the orientation on the finest level (orient_from_finest).
  LevelTurns(int bands, bool orient_finest)
      : turns_(static_cast<std::size_t>(bands)), bands_(bands), orient_finest_(orient_finest) {}

  // Level l-1 is built: its points (level), its unoriented normals and, in support[l-1], its
  // support; support[l] is the finer level's. original: the points' input numbers
  // (cluster_layout.h), by which the finer support's frames list each cluster's points.
  // cluster_normals: needed for the finest level (the first added) with orient_finest: its
  // clusters' normals at their anchors (#C by 3, either sign; the projection's), which it orients.
  void add(int l, const Points& level, Points normals, const std::vector<LevelSupport>& support,
           const IndexList& original, Points* cluster_normals = nullptr);

  // Orients level 0's normals like reference0(i) (a Vec3 per point; flip where n . reference
  // < 0), and each finer level where its turn against the oriented level below is negative,
  // which is the sign of n_l . n_{l-1} (negating a vector negates a dot product exactly, so this
  // is the very test reconstruction makes). Each flip negates the point's detail in that band
  // (details k by #P), so detail x normal is unchanged. Returns level 0's oriented normals.
  template <class Reference>
  Points orient(Eigen::MatrixXd& details, const Reference& reference0);

  // The anchors of the level added last (level 0 once all are added).
  const Points& last_anchors() const { return finer_anchors_; }
  // Level 0's unoriented normals, #P by 3, until orient.
  const Points& level0_normals() const { return normals0_; }

  // Per point, whether level 0's unoriented normal must flip for the finest level to agree,
  // through the turns at that point, with its clusters' anchor normals oriented by
  // spanning-tree propagation (level_orientation.h) when it was added. Needs orient_finest.
  // Where two levels' normals are nearly at right angles (the walls of tall detail over a
  // flat base) a turn's sign is a toss-up, so decompose takes these per level-0 cluster, by a
  // vote of its points.
  std::vector<unsigned char> level0_flips_from_finest() const;
  // Per point, the smallest |n_l . n_{l-1}| over its turns (1 for one band): how sure the
  // chain of level0_flips_from_finest is there. Needs orient_finest.
  const std::vector<float>& turn_sureness() const { return sureness_; }

 private:
  // Flips level 0 where flipped[i], then each finer level by its turns (orient, above).
  Points orient_upward(Eigen::MatrixXd& details, std::vector<unsigned char>& flipped);


  using FloatNormals = Eigen::Matrix<float, Eigen::Dynamic, 3, Eigen::RowMajor>;
  FloatNormals finer_normals_;  // the level built last, in single precision (not level 0)
  Points finer_anchors_;        // its anchors
  Points normals0_;             // level 0's unoriented normals
  std::vector<std::vector<signed char>> turns_;  // turns_[l]: sign of n_l . n_{l-1} per point
  std::vector<unsigned char> finest_flipped_;    // per point: the finest level's normal faces in
  std::vector<float> sureness_;                  // per point: turn_sureness
  int bands_;
  bool orient_finest_;
};

template <class Reference>
Points LevelTurns::orient(Eigen::MatrixXd& details, const Reference& reference0) {
  const Eigen::Index n = details.cols();
  std::vector<unsigned char> flipped(static_cast<std::size_t>(n));
  for (Eigen::Index i = 0; i < n; ++i) flipped[i] = normals0_.row(i).dot(reference0(i).transpose()) < 0.0;
  return orient_upward(details, flipped);
}

}  // namespace pointscale
