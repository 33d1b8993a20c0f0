#pragma once

#include <cmath>
#include <string>

#include "core/esdf/esdf_config.h"

namespace cblox {

/// Settings of the mapper's planning map (MapperConfig::planning, planning_map.h). Plain
/// value type.
struct PlanningConfig {
  /// Keep a distance field per subvolume and answer distance queries (Mapper::planningMap).
  /// Off (the default): no field, no memory, Mapper::planningMap() is null. Off by default
  /// while the waves' working memory is outside the memory cap's accounting.
  bool enabled = false;
  /// The fields' settings.
  EsdfConfig esdf;
  /// The fields follow the map every this many seconds, on the fusion/export worker
  /// (PlanningMap::refresh); finite and > 0.
  double refresh_period_s = 0.5;

  /// Empty when valid, otherwise a message naming the offending field. Thread-safe.
  std::string validate() const {
    if (const std::string e = esdf.validate(); !e.empty()) return "planning." + e;
    if (!std::isfinite(refresh_period_s) || !(refresh_period_s > 0.0)) {
      return "planning.refresh_period_s must be finite and > 0, got " +
             std::to_string(refresh_period_s);
    }
    return {};
  }
};

}  // namespace cblox
