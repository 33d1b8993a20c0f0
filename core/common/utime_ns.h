#pragma once

#include <algorithm>
#include <chrono>
#include <cstdint>

namespace cblox {

/// A bus time stamp in microseconds as nanoseconds, clamped to +-292 years first: a hostile
/// stamp would overflow int64 when multiplied. Thread-safe (pure).
inline int64_t utimeToNs(int64_t utime) {
  return std::clamp<int64_t>(utime, INT64_MIN / 1000, INT64_MAX / 1000) * 1000;
}

/// Wall-clock time in microseconds since the Unix epoch (LCM message time stamps, map
/// epochs). Thread-safe.
inline int64_t wallUtime() {
  return std::chrono::duration_cast<std::chrono::microseconds>(
             std::chrono::system_clock::now().time_since_epoch())
      .count();
}

}  // namespace cblox
