#pragma once

#include <algorithm>
#include <cstddef>
#include <deque>
#include <mutex>
#include <vector>

namespace cblox {

/// The last `capacity` durations (milliseconds) and their quantiles, for status reports.
/// Thread-safety: all member functions are thread-safe (one mutex).
class TimingWindow {
 public:
  explicit TimingWindow(size_t capacity) : capacity_(capacity < 1 ? 1 : capacity) {}

  void add(double ms) {
    std::lock_guard<std::mutex> lock(mutex_);
    values_.push_back(ms);
    while (values_.size() > capacity_) values_.pop_front();
  }

  /// The newest value; 0 when empty.
  double last() const {
    std::lock_guard<std::mutex> lock(mutex_);
    return values_.empty() ? 0.0 : values_.back();
  }

  /// The q-quantile (q in [0, 1]) of the kept values, nearest rank; 0 when empty.
  double quantile(double q) const {
    std::vector<double> sorted;
    {
      std::lock_guard<std::mutex> lock(mutex_);
      sorted.assign(values_.begin(), values_.end());
    }
    if (sorted.empty()) return 0.0;
    const size_t rank = std::min(
        sorted.size() - 1, static_cast<size_t>(q * static_cast<double>(sorted.size() - 1) + 0.5));
    std::nth_element(sorted.begin(), sorted.begin() + static_cast<std::ptrdiff_t>(rank),
                     sorted.end());
    return sorted[rank];
  }

 private:
  const size_t capacity_;
  mutable std::mutex mutex_;
  std::deque<double> values_;
};

}  // namespace cblox
