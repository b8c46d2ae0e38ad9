// Shared array types of the core. Points are row-major so that a NumPy (n,3) C array maps onto them.
#pragma once
#include <Eigen/Core>
#include <cstdint>
#include <vector>

namespace pointscale {

using Vec3 = Eigen::Vector3d;
using Mat3 = Eigen::Matrix3d;
// #P by 3, one point per row.
using Points = Eigen::Matrix<double, Eigen::Dynamic, 3, Eigen::RowMajor>;
using Index = std::int32_t;
using IndexList = std::vector<Index>;

}  // namespace pointscale
