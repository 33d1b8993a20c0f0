#include "core/tsdf/tsdf_interpolator.h"

#include <algorithm>
#include <cmath>

namespace cblox {

bool TsdfInterpolator::getNearestDistance(const Eigen::Vector3f& point, float* distance) const {
  const TsdfVoxel* voxel = layer_.getVoxelAtPoint(point);
  if (voxel == nullptr || !voxel->observed()) return false;
  *distance = voxel->distance;
  return true;
}

bool TsdfInterpolator::getInterpolatedDistance(const Eigen::Vector3f& point, float* distance,
                                               Color* color, float* weight) const {
  // Position in voxel units relative to voxel centres: centre of voxel i is at i + 0.5.
  const Eigen::Vector3f scaled = point * layer_.voxelSizeInv() - Eigen::Vector3f::Constant(0.5f);
  const Eigen::Vector3f floor_scaled(std::floor(scaled.x()), std::floor(scaled.y()),
                                     std::floor(scaled.z()));
  const GlobalVoxelIndex base = floor_scaled.cast<int>();
  const Eigen::Vector3f frac = scaled - floor_scaled;

  float sum_distance = 0.0f;
  float sum_weight = 0.0f;
  Eigen::Vector3f sum_color = Eigen::Vector3f::Zero();
  for (int corner = 0; corner < 8; ++corner) {
    const GlobalVoxelIndex offset(corner & 1, (corner >> 1) & 1, (corner >> 2) & 1);
    const TsdfVoxel* voxel = layer_.getVoxel(GlobalVoxelIndex(base + offset));
    if (voxel == nullptr || !voxel->observed()) return false;
    const float w = (offset.x() ? frac.x() : 1.0f - frac.x()) *
                    (offset.y() ? frac.y() : 1.0f - frac.y()) *
                    (offset.z() ? frac.z() : 1.0f - frac.z());
    sum_distance += w * voxel->distance;
    sum_weight += w * voxel->weight;
    sum_color += w * Eigen::Vector3f(voxel->color.r, voxel->color.g, voxel->color.b);
  }
  *distance = sum_distance;
  if (weight != nullptr) *weight = sum_weight;
  if (color != nullptr) {
    color->r = static_cast<uint8_t>(std::lround(std::clamp(sum_color.x(), 0.0f, 255.0f)));
    color->g = static_cast<uint8_t>(std::lround(std::clamp(sum_color.y(), 0.0f, 255.0f)));
    color->b = static_cast<uint8_t>(std::lround(std::clamp(sum_color.z(), 0.0f, 255.0f)));
  }
  return true;
}

}  // namespace cblox
