#pragma once

#include <cstdint>

#include "core/geometry/color.h"

namespace cblox {

/// One TSDF voxel: truncated signed distance (metres, positive in front of the surface,
/// i.e. on the sensor side), fusion weight (0 = never observed) and blended colour.
/// 12 bytes; trivially copyable. Not thread-safe: writers hold the owning block's lock
/// or own the block exclusively.
struct TsdfVoxel {
  float distance = 0.0f;
  float weight = 0.0f;
  Color color;
  uint8_t padding = 0;

  bool observed() const { return weight > 0.0f; }
};
static_assert(sizeof(TsdfVoxel) == 12, "TsdfVoxel must stay 12 bytes");

}  // namespace cblox
