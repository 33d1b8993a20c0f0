#include "drivers/camera/timestamp_mapping.h"

#include <time.h>

#include <algorithm>
#include <utility>
#include <vector>

namespace cblox {
namespace {

int64_t readClockNs(clockid_t clock) {
  timespec ts{};
  clock_gettime(clock, &ts);
  return static_cast<int64_t>(ts.tv_sec) * 1'000'000'000 + static_cast<int64_t>(ts.tv_nsec);
}

}  // namespace

int64_t timevalToNs(const timeval& tv) {
  return static_cast<int64_t>(tv.tv_sec) * 1'000'000'000 + static_cast<int64_t>(tv.tv_usec) * 1'000;
}

std::optional<ClockOffset> estimateClockOffset(std::span<const ClockSample> samples) {
  const ClockSample* best = nullptr;
  for (const ClockSample& sample : samples) {
    const int64_t width = sample.realtime_after_ns - sample.realtime_before_ns;
    if (width < 0) continue;
    if (best == nullptr || width < best->realtime_after_ns - best->realtime_before_ns) {
      best = &sample;
    }
  }
  if (best == nullptr) return std::nullopt;
  const int64_t width = best->realtime_after_ns - best->realtime_before_ns;
  const int64_t midpoint = best->realtime_before_ns + width / 2;
  return ClockOffset{midpoint - best->monotonic_ns, (width + 1) / 2, best->monotonic_ns};
}

ClockSample readSystemClocks() {
  ClockSample sample;
  sample.realtime_before_ns = readClockNs(CLOCK_REALTIME);
  sample.monotonic_ns = readClockNs(CLOCK_MONOTONIC);
  sample.realtime_after_ns = readClockNs(CLOCK_REALTIME);
  return sample;
}

MonotonicClockMapping::MonotonicClockMapping(ClockMappingOptions options, Sampler sampler)
    : options_(options), sampler_(std::move(sampler)) {
  options_.samples_per_estimate = std::max(options_.samples_per_estimate, 1);
  options_.refresh_interval_ns = std::max<int64_t>(options_.refresh_interval_ns, 0);
}

bool MonotonicClockMapping::refresh() {
  std::vector<ClockSample> samples;
  samples.reserve(static_cast<size_t>(options_.samples_per_estimate));
  for (int i = 0; i < options_.samples_per_estimate; ++i) samples.push_back(sampler_());
  last_attempt_ns_ = samples.back().monotonic_ns;
  std::optional<ClockOffset> estimate = estimateClockOffset(samples);
  if (!estimate) return false;
  offset_ = estimate;
  return true;
}

int64_t MonotonicClockMapping::toRealtimeNs(int64_t monotonic_ns) {
  // Judge staleness by the timestamp being converted: frames arrive within milliseconds of
  // their capture, and this avoids reading the clock for every frame.
  if (!last_attempt_ns_ || monotonic_ns - *last_attempt_ns_ >= options_.refresh_interval_ns) {
    refresh();
  }
  return offset_ ? monotonic_ns + offset_->offset_ns : monotonic_ns;
}

}  // namespace cblox
