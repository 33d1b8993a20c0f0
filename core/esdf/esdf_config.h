#pragma once

#include <string>

namespace cblox {

/// Settings of one subvolume's distance field (EsdfIntegrator).
struct EsdfConfig {
  /// Distances are computed up to this far from the nearest obstacle, metres; a free voxel
  /// farther away holds exactly max_distance_m ("at least this far"). Finite and > 0.
  float max_distance_m = 2.0f;
  /// A TSDF voxel with weight below this is unknown space: neither free nor an obstacle.
  /// Finite and >= 0.
  float min_weight = 1e-4f;

  /// Empty when valid, otherwise a message naming the offending field. Thread-safe.
  std::string validate() const;
};

}  // namespace cblox
