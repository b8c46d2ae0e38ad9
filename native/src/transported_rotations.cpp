#include "pointscale/detail/transported_rotations.h"

#include <Eigen/LU>
#include <Eigen/SVD>
#include <cmath>

#include "pointscale/parallel.h"
#include "pointscale/detail/level_normals.h"

namespace pointscale {

std::vector<Mat3> transported_rotations(const Points& original, const Points& edited, const LevelSupport& support,
                                        std::vector<signed char>* orientation) {
  const Points b0 = support_centroids(original, support);
  const Points b1 = support_centroids(edited, support);
  const int k = support.neighbors;
  // The rotation that best maps each cluster's neighbourhood from the original to the edited
  // level (Kabsch). Unedited it is the identity, so the references are the stored normals.
  std::vector<Mat3> rotation(static_cast<std::size_t>(support.clusters));
  if (orientation) orientation->assign(rotation.size(), 0);
  parallel_for(rotation.size(), [&](std::size_t b, std::size_t e) {
    for (std::size_t cc = b; cc < e; ++cc) {
      const Index c = static_cast<Index>(cc);
      const Index* nb = support.neighborhoods.data() + static_cast<std::size_t>(c) * k;
      const double h = support.h(c);
      rotation[cc] = Mat3::Identity();
      // A neighbourhood the edit left as it was keeps the identity exactly, without a solve.
      bool same = b0.row(c) == b1.row(c);
      for (int j = 1; j < k && same; ++j) same = b0.row(nb[j]) == b1.row(nb[j]);
      if (same) {
        if (orientation) (*orientation)[cc] = 2;  // left alone: no mirror of the part moves it so
        continue;
      }
      Mat3 cov = Mat3::Zero();
      for (int j = 1; j < k; ++j) {
        const Vec3 e0 = (b0.row(nb[j]) - b0.row(c)).transpose();
        const Vec3 e1 = (b1.row(nb[j]) - b1.row(c)).transpose();
        cov.noalias() += std::exp(-e0.squaredNorm() / (h * h)) * e0 * e1.transpose();
      }
      const Eigen::JacobiSVD<Mat3> svd(cov, Eigen::ComputeFullU | Eigen::ComputeFullV);
      const Eigen::Vector3d s = svd.singularValues();
      // A neighbourhood on a line does not fix the rotation about it: keep the identity there.
      if (!(s(1) > 1e-9 * s(0))) continue;
      Mat3 d = Mat3::Identity();
      d(2, 2) = (svd.matrixV() * svd.matrixU().transpose()).determinant() < 0 ? -1.0 : 1.0;
      if (orientation && s(2) >= 1e-2 * s(0)) (*orientation)[cc] = static_cast<signed char>(d(2, 2));
      rotation[cc] = svd.matrixV() * d * svd.matrixU().transpose();
    }
  }, {}, 64);  // small chunks: level 0 has few clusters, and large chunks would load the threads unevenly
  return rotation;
}

}  // namespace pointscale
