#include "core/mapping/planning_config.h"

#include <cmath>

#include "core/common/text_format.h"
#include "core/mapping/planning_map.h"

namespace cblox {

std::string PlanningServiceConfig::validate() const {
  if (max_points < 1) return "service.max_points must be >= 1";
  if (queue_capacity < 1) return "service.queue_capacity must be >= 1";
  if (query_threads < 1 || query_threads > 16) {
    return "service.query_threads must be in [1, 16], got " + std::to_string(query_threads);
  }
  if (!std::isfinite(grid_period_s) || grid_period_s < 0.0) {
    return "service.grid_period_s must be finite and >= 0, got " + std::to_string(grid_period_s);
  }
  if (!std::isfinite(grid_resolution_m) || !(grid_resolution_m > 0.0)) {
    return "service.grid_resolution_m must be finite and > 0, got " +
           std::to_string(grid_resolution_m);
  }
  double cells = 1.0;
  for (int a = 0; a < 3; ++a) {
    if (!std::isfinite(grid_size_m[a]) || !(grid_size_m[a] > 0.0)) {
      return "service.grid_size_m must hold three finite values > 0";
    }
    cells *= std::ceil(grid_size_m[a] / grid_resolution_m);
  }
  if (cells > static_cast<double>(PlanningMap::kMaxGridCells)) {
    return "service.grid_size_m / grid_resolution_m make " + significant(cells, 3) +
           " cells, more than " + std::to_string(PlanningMap::kMaxGridCells);
  }
  return {};
}

std::string PlanningConfig::validate() const {
  EsdfConfig resolved = esdf;
  resolved.band_blocks = bandBlocks(0.0);
  if (const std::string e = resolved.validate(); !e.empty()) return "planning." + e;
  if (!std::isfinite(refresh_period_s) || !(refresh_period_s > 0.0)) {
    return "planning.refresh_period_s must be finite and > 0, got " +
           std::to_string(refresh_period_s);
  }
  if (const std::string e = service.validate(); !e.empty()) return "planning." + e;
  return {};
}

}  // namespace cblox
