#pragma once

// When a process's input source restarted: its time stamps went back by more than a set
// number of seconds (the mapper's and the tracker's restart_after_backwards_s).

#include <climits>
#include <cstdint>

namespace cblox {

/// Seconds from `utime` back to `newest_utime` (positive when `utime` is older), in double:
/// two time stamps from the bus may be 2^63 apart, which int64_t arithmetic would overflow.
/// Thread-safe (pure).
inline double secondsBack(int64_t newest_utime, int64_t utime) {
  return (static_cast<double>(newest_utime) - static_cast<double>(utime)) * 1e-6;
}

/// True when `utime` is more than `restart_after_backwards_s` (> 0; otherwise never) older
/// than `newest_utime` (INT64_MIN: nothing yet): the source restarted. Thread-safe (pure).
inline bool isTimeRestart(int64_t newest_utime, int64_t utime, double restart_after_backwards_s) {
  if (restart_after_backwards_s <= 0.0 || newest_utime == INT64_MIN) return false;
  return secondsBack(newest_utime, utime) > restart_after_backwards_s;
}

}  // namespace cblox
