#include "drivers/camera/reopen_schedule.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <stdexcept>

namespace cblox {
namespace {

int64_t secondsToNs(double seconds) { return static_cast<int64_t>(std::llround(seconds * 1e9)); }

}  // namespace

double reopenDelaySeconds(int attempt, double min_s, double max_s) {
  const int doublings = std::clamp(attempt, 1, 64) - 1;
  return std::min(std::ldexp(min_s, doublings), max_s);
}

int64_t steadyNowNs() {
  return std::chrono::duration_cast<std::chrono::nanoseconds>(
             std::chrono::steady_clock::now().time_since_epoch())
      .count();
}

std::string formatSeconds(double seconds) {
  const double tenths = std::max(0.0, std::ceil(seconds * 10.0 - 1e-9));  // never -0
  char text[32];
  if (std::fmod(tenths, 10.0) == 0.0) {
    std::snprintf(text, sizeof(text), "%.0f", tenths / 10.0);
  } else {
    std::snprintf(text, sizeof(text), "%.1f", tenths / 10.0);
  }
  return text;
}

ReopenSchedule::ReopenSchedule(double min_s, double max_s) : min_s_(min_s), max_s_(max_s) {
  if (!(min_s > 0.0) || !(max_s >= min_s) || !std::isfinite(max_s)) {
    throw std::invalid_argument("ReopenSchedule: need 0 < min_s <= max_s, got " +
                                std::to_string(min_s) + ", " + std::to_string(max_s));
  }
}

void ReopenSchedule::lost(int64_t now_ns) {
  if (reopening_) return;
  reopening_ = true;
  attempt_ = 1;
  next_attempt_ns_ = now_ns + secondsToNs(reopenDelaySeconds(1, min_s_, max_s_));
}

void ReopenSchedule::failed(int64_t now_ns) {
  ++total_attempts_;
  if (!reopening_) return;
  ++attempt_;
  next_attempt_ns_ = now_ns + secondsToNs(reopenDelaySeconds(attempt_, min_s_, max_s_));
}

void ReopenSchedule::succeeded() {
  ++total_attempts_;
  reopening_ = false;
  attempt_ = 0;
}

std::string ReopenSchedule::status(const std::string& device, int64_t now_ns) const {
  if (!reopening_) return {};
  const double remaining_s =
      static_cast<double>(std::max<int64_t>(next_attempt_ns_ - now_ns, 0)) * 1e-9;
  return "reopening " + device + " (attempt " + std::to_string(attempt_) + ", next in " +
         formatSeconds(remaining_s) + " s)";
}

}  // namespace cblox
