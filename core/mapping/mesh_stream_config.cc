#include "core/mapping/mesh_stream_config.h"

#include <cmath>

namespace cblox {

std::string MeshStreamConfig::validate() const {
  if (!std::isfinite(period_s) || period_s < 0.05 || period_s > 60.0) {
    return "period_s must be in [0.05, 60], got " + std::to_string(period_s);
  }
  if (max_message_bytes < (size_t{4} << 10) || max_message_bytes >= (size_t{4} << 20)) {
    return "max_message_bytes must be in [4096, 4194304), got " +
           std::to_string(max_message_bytes);
  }
  if (max_bytes_per_period < max_message_bytes) {
    return "max_bytes_per_period (" + std::to_string(max_bytes_per_period) +
           ") must be at least max_message_bytes (" + std::to_string(max_message_bytes) + ")";
  }
  if (!std::isfinite(refresh_period_s) || refresh_period_s < 0.0 ||
      (refresh_period_s > 0.0 && refresh_period_s < period_s)) {
    return "refresh_period_s must be 0 or at least period_s, got " +
           std::to_string(refresh_period_s);
  }
  return {};
}

}  // namespace cblox
