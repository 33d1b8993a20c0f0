#pragma once

// The order statistic the evaluation tools report as "median" and "p90". Header-only (no
// link dependency), so drivers and benchmarks share it.

#include <algorithm>
#include <cstddef>
#include <vector>

namespace cblox {

/// The element of rank min(n - 1, floor(q * n)) of *values (q in [0, 1]; 0.5 is the upper
/// median for an even count), found by partial sorting: *values is reordered. 0 when empty.
/// Thread-safe as *values is.
inline double quantile(std::vector<double>* values, double q) {
  if (values->empty()) return 0.0;
  const size_t k = std::min(values->size() - 1, static_cast<size_t>(q * values->size()));
  std::nth_element(values->begin(), values->begin() + static_cast<std::ptrdiff_t>(k),
                   values->end());
  return (*values)[k];
}

}  // namespace cblox
