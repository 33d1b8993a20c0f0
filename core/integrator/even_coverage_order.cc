#include "core/integrator/even_coverage_order.h"

#include <bit>

namespace cblox {

std::vector<uint32_t> evenCoverageOrder(uint32_t n) {
  std::vector<uint32_t> order;
  if (n == 0) return order;
  order.reserve(n);
  const int bits = std::bit_width(n - 1);  // 2^bits >= n
  const uint64_t count = uint64_t{1} << bits;
  for (uint64_t i = 0; i < count; ++i) {
    uint32_t reversed = 0;
    for (int b = 0; b < bits; ++b)
      reversed |= static_cast<uint32_t>((i >> b) & 1u) << (bits - 1 - b);
    if (reversed < n) order.push_back(reversed);
  }
  return order;
}

}  // namespace cblox
