#pragma once

#include <chrono>

namespace cblox {

/// A point in time after which work should stop; `seconds` <= 0 means never.
/// Thread-safe (immutable after construction).
class Deadline {
 public:
  using Clock = std::chrono::steady_clock;
  explicit Deadline(double seconds)
      : unlimited_(seconds <= 0.0),
        end_(Clock::now() + std::chrono::duration_cast<Clock::duration>(
                                std::chrono::duration<double>(unlimited_ ? 0.0 : seconds))) {}
  bool expired() const { return !unlimited_ && Clock::now() >= end_; }

 private:
  bool unlimited_;
  Clock::time_point end_;
};

}  // namespace cblox
