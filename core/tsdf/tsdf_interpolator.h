#pragma once

#include <Eigen/Core>

#include "core/geometry/color.h"
#include "core/tsdf/tsdf_layer.h"

namespace cblox {

/// Point queries on a TSDF layer. Thread-safe as long as the layer is not being modified
/// (the interpolator only reads).
class TsdfInterpolator {
 public:
  explicit TsdfInterpolator(const TsdfLayer& layer) : layer_(layer) {}

  /// Distance of the voxel containing `point` (no interpolation). False when the voxel
  /// is unallocated or unobserved (weight 0).
  bool getNearestDistance(const Eigen::Vector3f& point, float* distance) const;

  /// Trilinear interpolation of distance (and colour, when `color` is not null) between
  /// the 8 voxel centres surrounding `point`. False unless all 8 are observed.
  /// At a voxel centre the result equals that voxel's distance exactly.
  bool getInterpolatedDistance(const Eigen::Vector3f& point, float* distance,
                               Color* color = nullptr, float* weight = nullptr) const;

 private:
  const TsdfLayer& layer_;
};

}  // namespace cblox
