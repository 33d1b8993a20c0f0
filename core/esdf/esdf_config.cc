#include "core/esdf/esdf_config.h"

#include <cmath>

namespace cblox {

std::string EsdfConfig::validate() const {
  if (!std::isfinite(max_distance_m) || !(max_distance_m > 0.0f)) {
    return "max_distance_m must be finite and > 0, got " + std::to_string(max_distance_m);
  }
  if (!std::isfinite(min_weight) || min_weight < 0.0f) {
    return "min_weight must be finite and >= 0, got " + std::to_string(min_weight);
  }
  if (band_blocks < 0 || band_blocks > 2) {
    return "band_blocks must be in [0, 2], got " + std::to_string(band_blocks);
  }
  if (!std::isfinite(surface_margin_voxels) || surface_margin_voxels < 0.0f ||
      surface_margin_voxels > 1.0f) {
    return "surface_margin_voxels must be in [0, 1], got " + std::to_string(surface_margin_voxels);
  }
  return {};
}

}  // namespace cblox
