#include "pointscale/detail/transported_rotations.h"

#include <Eigen/LU>
#include <Eigen/SVD>
#include <cmath>

#include "pointscale/parallel.h"
#include "pointscale/detail/level_normals.h"

namespace pointscale {

bool neighbourhood_cross(const Points& b0, const Points& b1, const LevelSupport& support, Index c, Mat3& cov) {
  const int k = support.neighbors;
  const Index* nb = support.neighborhoods.data() + static_cast<std::size_t>(c) * k;
  bool same = b0.row(c) == b1.row(c);
  for (int j = 1; j < k && same; ++j) same = b0.row(nb[j]) == b1.row(nb[j]);
  if (same) return false;
  const double h = support.h(c);
  cov = Mat3::Zero();
  for (int j = 1; j < k; ++j) {
    const Vec3 e0 = (b0.row(nb[j]) - b0.row(c)).transpose();
    const Vec3 e1 = (b1.row(nb[j]) - b1.row(c)).transpose();
    cov.noalias() += std::exp(-e0.squaredNorm() / (h * h)) * e0 * e1.transpose();
  }
  return true;
}

signed char orientation_vote(const Eigen::JacobiSVD<Mat3>& svd) {
  const Vec3 s = svd.singularValues();
  if (!(s(1) > 1e-9 * s(0)) || !(s(2) >= 1e-2 * s(0))) return 0;
  return (svd.matrixV() * svd.matrixU().transpose()).determinant() < 0.0 ? -1 : 1;
}

std::vector<Mat3> transported_rotations(const Points& original, const Points& edited, const LevelSupport& support,
                                        std::vector<signed char>* orientation) {
  const Points b0 = support_centroids(original, support);
  const Points b1 = support_centroids(edited, support);
  // The rotation that best maps each cluster's neighbourhood from the original to the edited
  // level (Kabsch). Unedited it is the identity, so the references are the stored normals.
  std::vector<Mat3> rotation(static_cast<std::size_t>(support.clusters));
  if (orientation) orientation->assign(rotation.size(), 0);
  parallel_for(rotation.size(), [&](std::size_t b, std::size_t e) {
    for (std::size_t cc = b; cc < e; ++cc) {
      rotation[cc] = Mat3::Identity();
      // A neighbourhood the edit left as it was keeps the identity exactly, without a solve.
      Mat3 cov;
      if (!neighbourhood_cross(b0, b1, support, static_cast<Index>(cc), cov)) {
        if (orientation) (*orientation)[cc] = 2;  // left alone: no mirror of the part moves it so
        continue;
      }
      const Eigen::JacobiSVD<Mat3> svd(cov, Eigen::ComputeFullU | Eigen::ComputeFullV);
      const Eigen::Vector3d s = svd.singularValues();
      // A neighbourhood on a line does not fix the rotation about it: keep the identity there.
      if (!(s(1) > 1e-9 * s(0))) continue;
      Mat3 d = Mat3::Identity();
      d(2, 2) = (svd.matrixV() * svd.matrixU().transpose()).determinant() < 0 ? -1.0 : 1.0;
      if (orientation) (*orientation)[cc] = orientation_vote(svd);
      rotation[cc] = svd.matrixV() * d * svd.matrixU().transpose();
    }
  }, {}, 64);  // small chunks: level 0 has few clusters, and large chunks would load the threads unevenly
  return rotation;
}

}  // namespace pointscale
