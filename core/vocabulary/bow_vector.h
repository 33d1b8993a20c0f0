#pragma once

#include <cstdint>
#include <utility>
#include <vector>

namespace cblox {

/// Index of a word (a leaf of the vocabulary tree), in [0, wordCount()).
using WordId = uint32_t;
/// Index of a node of the vocabulary tree (0 = root), in [0, nodeCount()).
using NodeId = uint32_t;

/// Bag-of-words vector of one image: (word, tf-idf weight) pairs sorted by word id, each word
/// once, weights > 0 and summing to 1 (L1-normalised); empty for an image without words.
/// Plain value type.
using BowVector = std::vector<std::pair<WordId, double>>;

/// Direct index of one image: (node, indices of the image's features whose word lies under
/// that node) sorted by node id, indices ascending. The nodes lie a fixed number of levels
/// above the leaves (see BinaryVocabulary::transform). Two images' features need only be
/// compared within the same node (guided matching, ORB-SLAM2's SearchByBoW). Plain value.
using FeatureVector = std::vector<std::pair<NodeId, std::vector<uint32_t>>>;

/// DBoW2's L1 score of two L1-normalised BoW vectors: 1 - 0.5 * sum_i |a_i - b_i|, in [0, 1]:
/// 1 for equal vectors, 0 for vectors without a common word. Computed over the common words
/// only (= sum_i min(a_i, b_i) for normalised vectors), O(|a| + |b|). Thread-safe (pure).
double scoreL1(const BowVector& a, const BowVector& b);

/// Number of words two BoW vectors share. O(|a| + |b|). Thread-safe (pure).
int sharedWordCount(const BowVector& a, const BowVector& b);

}  // namespace cblox
