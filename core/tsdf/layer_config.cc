#include "core/tsdf/layer_config.h"

#include <cmath>
#include <sstream>

namespace cblox {

std::string LayerConfig::validate() const {
  std::ostringstream error;
  if (!std::isfinite(voxel_size) || voxel_size <= 0.0f) {
    error << "voxel_size must be finite and > 0, got " << voxel_size;
  } else if (voxels_per_side < 2 || voxels_per_side > 64 ||
             (voxels_per_side & (voxels_per_side - 1)) != 0) {
    error << "voxels_per_side must be a power of two in [2, 64], got " << voxels_per_side;
  }
  return error.str();
}

}  // namespace cblox
