#pragma once

#include "core/vocabulary/bow_vector.h"

namespace cblox {

/// Calls f(indices_in_a, indices_in_b) for every vocabulary node the two FeatureVectors share
/// (both sorted by node id, as BinaryVocabulary::transform makes them), in increasing node
/// order: the walk of ORB-SLAM2's BoW-guided matchers (SearchByBoW,
/// SearchForTriangulation). Thread-safe when f is (reads a and b only).
template <typename F>
void forCommonNodes(const FeatureVector& a, const FeatureVector& b, F f) {
  auto ia = a.begin();
  auto ib = b.begin();
  while (ia != a.end() && ib != b.end()) {
    if (ia->first == ib->first) {
      f(ia->second, ib->second);
      ++ia;
      ++ib;
    } else if (ia->first < ib->first) {
      ++ia;
    } else {
      ++ib;
    }
  }
}

}  // namespace cblox
