#include "pointscale/detail/mirrored_edit.h"

#include <Eigen/LU>
#include <Eigen/SVD>
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>

#include "pointscale/parallel.h"

namespace pointscale {

namespace {

// Sums over one part's points, in point order (one thread, so that the decision never
// depends on how a sum was split).
struct PartSums {
  Vec3 original = Vec3::Zero(), edited = Vec3::Zero();
  Mat3 cross = Mat3::Zero();  // sum (o - o_mean)(e - e_mean)^T
  double spread_original = 0.0, spread_edited = 0.0;  // sum |o - o_mean|^2, sum |e - e_mean|^2
  double count = 0.0;
};

// Whether the part's best similarity (a turn and a uniform scale) fits the edit at least four
// times worse than its best mirror-similarity (Kabsch with and without a reflection): with
// the singular values s1 >= s2 >= s3 of the cross sums, the two fit to within
// E - (s1 + s2 - s3)^2 / O and E - (s1 + s2 + s3)^2 / O where the best orthogonal map
// reverses orientation. A part that is flat (s3 = 0), or an edit that bends it far from any
// similarity (a lift on a plane), fits both alike: it counts as not mirrored.
bool mirrors(const PartSums& s) {
  if (s.count < 4.0 || !(s.spread_original > 0.0)) return false;
  const Eigen::JacobiSVD<Mat3> svd(s.cross, Eigen::ComputeFullU | Eigen::ComputeFullV);
  if (!((svd.matrixV() * svd.matrixU().transpose()).determinant() < 0.0)) return false;
  const Vec3 sv = svd.singularValues();
  const double mirror = sv(0) + sv(1) + sv(2), turn = sv(0) + sv(1) - sv(2);
  const double misfit_mirror = s.spread_edited - mirror * mirror / s.spread_original;
  const double misfit_turn = s.spread_edited - turn * turn / s.spread_original;
  return misfit_mirror < 0.25 * misfit_turn;
}

// How many points of a part the fits read, about: a sample. A mirror fits it exactly, and
// anything else fits far from four times better, so a sample decides as the whole part would,
// at a cost that does not grow with the model (a brush dab in an editing session redoes only a
// few thousand points).
constexpr double sampled_points = 4096.0;

// A point's place in the sample, from its stored base position alone, so that the same points
// are sampled in any point order.
std::uint64_t position_hash(const Points& original, Eigen::Index i) {
  std::uint64_t h = 0x9e3779b97f4a7c15ull;
  for (int a = 0; a < 3; ++a) {
    std::uint64_t bits;
    const double v = original(i, a) == 0.0 ? 0.0 : original(i, a);  // -0 and +0 alike
    std::memcpy(&bits, &v, sizeof bits);
    h ^= bits + 0x9e3779b97f4a7c15ull + (h << 6) + (h >> 2);
    h ^= h >> 31;
    h *= 0xbf58476d1ce4e5b9ull;
    h ^= h >> 29;
  }
  return h;
}

// The sums of each part over its sample, with the cross sums about the sample's centroids, in
// the sample's order.
std::vector<PartSums> part_sums(const Points& original, const Points& edited, const IndexList& parts,
                                const IndexList& sample) {
  auto part_of = [&](Index i) { return parts.empty() ? std::size_t(0) : static_cast<std::size_t>(parts[static_cast<std::size_t>(i)]); };
  Index labels = 1;
  for (Index p : parts) labels = std::max(labels, p + 1);
  std::vector<PartSums> sums(static_cast<std::size_t>(labels));
  for (Index i : sample) {
    PartSums& s = sums[part_of(i)];
    s.original += original.row(i).transpose();
    s.edited += edited.row(i).transpose();
    s.count += 1.0;
  }
  for (PartSums& s : sums)
    if (s.count > 0.0) { s.original /= s.count; s.edited /= s.count; }
  for (Index i : sample) {
    PartSums& s = sums[part_of(i)];
    const Vec3 o = original.row(i).transpose() - s.original, e = edited.row(i).transpose() - s.edited;
    s.cross.noalias() += o * e.transpose();
    s.spread_original += o.squaredNorm();
    s.spread_edited += e.squaredNorm();
  }
  return sums;
}

}  // namespace

IndexList mirror_sample(const Points& original, const IndexList& parts) {
  const std::size_t n = static_cast<std::size_t>(original.rows());
  Index labels = 1;
  for (Index p : parts) labels = std::max(labels, p + 1);
  std::vector<std::size_t> size(static_cast<std::size_t>(labels), 0);
  if (parts.empty()) size[0] = n;
  else
    for (Index p : parts) ++size[static_cast<std::size_t>(p)];
  std::vector<std::uint64_t> step(size.size());
  for (std::size_t p = 0; p < size.size(); ++p)
    step[p] = std::max<std::uint64_t>(1, static_cast<std::uint64_t>(std::ceil(static_cast<double>(size[p]) / sampled_points)));
  std::vector<std::pair<std::uint64_t, Index>> chosen;
  for (std::size_t i = 0; i < n; ++i) {
    const std::uint64_t h = position_hash(original, static_cast<Eigen::Index>(i));
    if (h % step[parts.empty() ? 0 : static_cast<std::size_t>(parts[i])] == 0) chosen.push_back({h, static_cast<Index>(i)});
  }
  // In the order of the hashes, ties (duplicated positions) by their point order.
  std::sort(chosen.begin(), chosen.end());
  IndexList sample(chosen.size());
  for (std::size_t k = 0; k < chosen.size(); ++k) sample[k] = chosen[k].second;
  return sample;
}

std::vector<unsigned char> mirrored_points(const Points& original, const Points& edited, const IndexList& parts,
                                           const IndexList& sample) {
  const std::vector<PartSums> sums = part_sums(original, edited, parts, sample);
  std::vector<unsigned char> part_mirrored(sums.size());
  bool any = false;
  for (std::size_t p = 0; p < sums.size(); ++p) any |= (part_mirrored[p] = mirrors(sums[p]) ? 1 : 0) != 0;
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
