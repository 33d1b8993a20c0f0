#pragma once

// Order statistics of the benchmarks' per-frame figures, and their clock.

#include <algorithm>
#include <chrono>
#include <cstddef>
#include <vector>

namespace cblox::bench {

/// Milliseconds of the steady clock since `start`.
inline double msSince(std::chrono::steady_clock::time_point start) {
  return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start)
      .count();
}

/// The median (the mean of the two middle values of an even count); 0 when empty.
inline double median(std::vector<double> v) {
  if (v.empty()) return 0.0;
  std::sort(v.begin(), v.end());
  return v.size() % 2 ? v[v.size() / 2] : 0.5 * (v[v.size() / 2 - 1] + v[v.size() / 2]);
}

/// The value at rank round(q * (n - 1)) of the sorted values, q in [0, 1]; 0 when empty.
inline double percentile(std::vector<double> v, double q) {
  if (v.empty()) return 0.0;
  std::sort(v.begin(), v.end());
  return v[std::min(v.size() - 1,
                    static_cast<size_t>(q * static_cast<double>(v.size() - 1) + 0.5))];
}

/// Keeps per frame the faster of two rounds of one configuration (`best` and `again` are
/// per-frame times of the same frames): the machine is shared, and interference only ever
/// adds time.
inline void keepFastestPerFrame(std::vector<double>* best, const std::vector<double>& again) {
  for (size_t i = 0; i < best->size() && i < again.size(); ++i) {
    (*best)[i] = std::min((*best)[i], again[i]);
  }
}

}  // namespace cblox::bench
