#pragma once

// Maps V4L2 buffer timestamps, taken on the kernel's CLOCK_MONOTONIC, to the system clock
// (CLOCK_REALTIME) that the rest of cblox stamps its messages with.

#include <sys/time.h>

#include <cstdint>
#include <functional>
#include <optional>
#include <span>

namespace cblox {

/// One reading of the clocks in the order realtime, monotonic, realtime (nanoseconds).
struct ClockSample {
  int64_t realtime_before_ns = 0;
  int64_t monotonic_ns = 0;
  int64_t realtime_after_ns = 0;
};

/// Offset realtime - monotonic and how well it is known. Plain value type.
struct ClockOffset {
  int64_t offset_ns = 0;       ///< realtime = monotonic + offset_ns
  int64_t uncertainty_ns = 0;  ///< half the width of the bracket it came from (>= 0)
  int64_t monotonic_ns = 0;    ///< when it was measured (monotonic clock)
};

/// struct timeval (as in v4l2_buffer::timestamp) to nanoseconds, exactly: tv_sec * 1e9 +
/// tv_usec * 1e3. Thread-safe (pure).
int64_t timevalToNs(const timeval& tv);

/// Estimates the offset from clock samples: of the samples whose bracket is well-formed
/// (realtime_after_ns >= realtime_before_ns), the tightest one (earliest of equals) gives
/// offset = midpoint of its realtime bracket - monotonic_ns (rounded toward the before
/// reading). std::nullopt when no sample is well-formed (e.g. the realtime clock stepped back
/// during every sample). Thread-safe (pure).
std::optional<ClockOffset> estimateClockOffset(std::span<const ClockSample> samples);

/// Reads CLOCK_REALTIME, CLOCK_MONOTONIC, CLOCK_REALTIME once. Thread-safe.
ClockSample readSystemClocks();

/// Options of MonotonicClockMapping. Plain value type.
struct ClockMappingOptions {
  int samples_per_estimate = 7;                 ///< >= 1 (smaller values count as 1)
  int64_t refresh_interval_ns = 1'000'000'000;  ///< >= 0; 0 re-estimates at every call
};

/// Converts monotonic timestamps to realtime with an offset re-estimated every
/// `refresh_interval_ns` of monotonic time (NTP slews and steps the realtime clock), each
/// time from `samples_per_estimate` clock samples. Not thread-safe: one thread uses it.
class MonotonicClockMapping {
 public:
  using Sampler = std::function<ClockSample()>;

  /// `sampler` reads the clocks (readSystemClocks by default; tests inject readings).
  explicit MonotonicClockMapping(ClockMappingOptions options = ClockMappingOptions(),
                                 Sampler sampler = readSystemClocks);

  /// Realtime nanoseconds of `monotonic_ns`. Estimates the offset first when no estimate was
  /// attempted yet or monotonic_ns lies at least the refresh interval after the monotonic
  /// reading of the last attempt (frames reach us milliseconds after capture, so the clocks
  /// need not be read for every frame); keeps the previous offset when a new estimate fails, and
  /// returns monotonic_ns + the offset (monotonic_ns unchanged if no estimate ever succeeded).
  int64_t toRealtimeNs(int64_t monotonic_ns);

  /// Re-estimates now; returns false (keeping the previous offset) when no sample was
  /// well-formed.
  bool refresh();

  /// The offset in use, if any.
  const std::optional<ClockOffset>& offset() const { return offset_; }

 private:
  ClockMappingOptions options_;
  Sampler sampler_;
  std::optional<ClockOffset> offset_;
  std::optional<int64_t> last_attempt_ns_;
};

}  // namespace cblox
