#include "core/geometry/point_cloud.h"

namespace cblox {

PointCloud transformPointCloud(const Transformation& T_A_B, const PointCloud& cloud_B) {
  const Eigen::Matrix3f R_A_B = T_A_B.rotationMatrix();
  const Eigen::Vector3f& t_A_B = T_A_B.translation();
  PointCloud cloud_A;
  cloud_A.points.reserve(cloud_B.points.size());
  for (const Eigen::Vector3f& p_B : cloud_B.points) {
    cloud_A.points.emplace_back(R_A_B * p_B + t_A_B);
  }
  cloud_A.colors = cloud_B.colors;
  return cloud_A;
}

}  // namespace cblox
