#include "core/vocabulary/bow_vector.h"

#include <algorithm>

namespace cblox {
namespace {

/// Calls on_common(weight_a, weight_b) for every word in both sorted vectors.
template <typename OnCommon>
void forEachCommonWord(const BowVector& a, const BowVector& b, OnCommon on_common) {
  auto ia = a.begin(), ib = b.begin();
  while (ia != a.end() && ib != b.end()) {
    if (ia->first < ib->first) {
      ++ia;
    } else if (ib->first < ia->first) {
      ++ib;
    } else {
      on_common(ia->second, ib->second);
      ++ia;
      ++ib;
    }
  }
}

}  // namespace

double scoreL1(const BowVector& a, const BowVector& b) {
  // For non-negative vectors with |a|_1 = |b|_1 = 1:
  // 1 - 0.5 * sum |a_i - b_i| = 0.5 * sum_common (a_i + b_i - |a_i - b_i|) = sum_common min.
  double score = 0.0;
  forEachCommonWord(a, b, [&score](double wa, double wb) { score += std::min(wa, wb); });
  return std::clamp(score, 0.0, 1.0);
}

int sharedWordCount(const BowVector& a, const BowVector& b) {
  int shared = 0;
  forEachCommonWord(a, b, [&shared](double, double) { ++shared; });
  return shared;
}

}  // namespace cblox
