#pragma once

#include <cstdint>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "core/features/orb_descriptor.h"
#include "core/vocabulary/bow_vector.h"

namespace cblox {

/// How a vocabulary tree is trained.
struct BinaryVocabularyConfig {
  /// k: children per node (clusters per k-majority split). [2, 64]. Default 10 (DBoW2 /
  /// ORB-SLAM2).
  int branching = 10;
  /// L: depth of the tree (levels below the root); at most k^L words. [1, 8], k^L <= 2^31.
  /// Default 6 (as ORB-SLAM2's vocabulary): on sim loops and real images it separates
  /// same-place from different-place scores clearly better than L = 4 or 5
  /// (core/vocabulary/README.md).
  int levels = 6;
  /// Seed of the k-means++ seeding; training is deterministic for a given seed and data.
  uint64_t seed = 1;
  /// Lloyd iterations per split before giving up on convergence. >= 1. Default 10.
  int max_iterations = 10;
  /// Threads train() uses for the subtrees of the root's children (>= 1). The result does not
  /// depend on it: each child's subtree has its own generator seeded from `seed`.
  int num_threads = 1;

  /// Empty when valid, otherwise a message naming the offending field. Thread-safe.
  std::string validate() const;
};

/// Figures of one training run.
struct BinaryVocabularyTrainingStats {
  size_t images = 0;
  size_t descriptors = 0;
  size_t nodes = 0;  ///< root included
  size_t words = 0;
  size_t splits = 0;              ///< k-majority runs
  size_t unconverged_splits = 0;  ///< runs stopped by max_iterations
  double seconds = 0.0;           ///< wall time of train()
};

/// A hierarchical vocabulary of binary words (DBoW2-like vocabulary tree over ORB
/// descriptors). Every node but the root holds a descriptor (its cluster's k-majority
/// centroid); the leaves are the words, numbered in node-id order. Each word has an idf weight
/// log(N / n_w) from the N training images (n_w: training images with a feature on word w;
/// weight 0, i.e. ignored by the BoW vector, for a word no training image reaches).
///
/// Word lookup descends from the root to the child at the smallest Hamming distance (ties:
/// the lowest node id) until a leaf: at most k * L distance computations (4 popcounts each)
/// per descriptor, 60 for k = 10, L = 6 (POPCNT: the build enables it on x86-64). Measured with
/// the default vocabulary (16 MB of node descriptors, so mostly cache misses): 0.6 ms for
/// the words of 1200 descriptors, 1.3 ms for transform() with BoW and feature vectors.
///
/// Thread-safety: immutable after train()/load(); all const methods are thread-safe.
class BinaryVocabulary {
 public:
  /// Levels above the leaves of the FeatureVector nodes by default: ORB-SLAM2's levelsup = 4,
  /// which with L = 6 gives nodes at depth 2 (at most k^2 = 100 buckets for guided matching).
  static constexpr int kDefaultFeatureLevelsUp = 4;

  /// Trains a vocabulary from the descriptors of a set of training images (one vector per
  /// image; the images define the idf weights): hierarchical k-majority clustering from the
  /// root, each node's descriptors split into at most k clusters by kMajorityCluster() until
  /// depth L, or a cluster with at most one descriptor, or data that no longer splits (all
  /// descriptors equal). The root is always split. `description` is stored (e.g. where the
  /// images came from). Deterministic for a config and data, whatever config.num_threads
  /// (threads it starts and joins itself). Cost O(n k L iterations) Hamming distances for n
  /// descriptors. Throws std::invalid_argument for an invalid config or when there is no
  /// descriptor at all. Thread-safe (pure).
  static BinaryVocabulary train(const std::vector<std::vector<OrbDescriptor>>& images,
                                const BinaryVocabularyConfig& config,
                                const std::string& description = "",
                                BinaryVocabularyTrainingStats* stats = nullptr);

  /// The word of one descriptor. Thread-safe.
  WordId wordOf(const OrbDescriptor& descriptor) const;

  /// The BoW vector of an image's features: sum of the idf weights of each feature's word
  /// (tf * idf), words of weight 0 left out, L1-normalised. Thread-safe.
  BowVector transform(const std::vector<OrbDescriptor>& features) const;

  /// As above, and the direct index: each feature's index under the node on its path that is
  /// `levels_up` levels above depth L (depth max(0, L - levels_up); the leaf itself when the
  /// leaf is shallower). levels_up = 0 gives the words themselves, >= L the root. Every
  /// feature is indexed, including those on zero-weight words. Either output may be null.
  /// Thread-safe.
  void transform(const std::vector<OrbDescriptor>& features, BowVector* bow,
                 FeatureVector* feature_vector, int levels_up = kDefaultFeatureLevelsUp) const;

  /// DBoW2's L1 score, 1 - 0.5 * sum |a_i - b_i| in [0, 1] (scoreL1). Thread-safe.
  static double score(const BowVector& a, const BowVector& b) { return scoreL1(a, b); }

  int branching() const { return branching_; }
  int levels() const { return levels_; }
  size_t wordCount() const { return word_node_.size(); }
  size_t nodeCount() const { return node_parent_.size(); }
  uint64_t trainingImageCount() const { return training_images_; }
  const std::string& description() const { return description_; }
  /// Centroid of a word (its leaf's descriptor); word < wordCount().
  const OrbDescriptor& wordDescriptor(WordId word) const;
  /// idf weight of a word; word < wordCount().
  double wordWeight(WordId word) const { return word_weight_[word]; }
  /// The leaf node of a word, the depth of a node (root 0) and its parent (the root's is
  /// the root).
  NodeId wordNode(WordId word) const { return word_node_[word]; }
  int nodeDepth(NodeId node) const { return node_depth_[node]; }
  NodeId nodeParent(NodeId node) const { return node == 0 ? 0 : node_parent_[node]; }

  /// The file image (format in binary_vocabulary_io.cc: magic, format version, k, L, node
  /// and word counts, description, node parents and descriptors, word weights, FNV-1a
  /// checksum; little-endian). Thread-safe.
  std::string serialize() const;
  /// Parses a file image; nullopt and a message for a wrong magic, an unsupported version, a
  /// truncated or oversized image, a checksum mismatch or an inconsistent tree. Thread-safe.
  static std::optional<BinaryVocabulary> deserialize(std::string_view bytes, std::string* error);
  /// Writes serialize() to `path` (false and a message naming the file on failure).
  bool save(const std::string& path, std::string* error) const;
  /// Reads a file written by save(); messages start with the path. Thread-safe.
  static std::optional<BinaryVocabulary> load(const std::string& path, std::string* error);

 private:
  static constexpr uint32_t kNoParent = 0xFFFFFFFFu;
  static constexpr WordId kNoWord = 0xFFFFFFFFu;

  BinaryVocabulary() = default;

  /// Descends to the leaf of `descriptor`; *at_depth = the node on the path at depth
  /// `depth` (the leaf if shallower) when not null.
  NodeId descend(const OrbDescriptor& descriptor, int depth, NodeId* at_depth) const;
  /// descend() for n <= kDescentBatch descriptors at once, their memory accesses interleaved
  /// (the same nodes as n calls of descend()).
  static constexpr size_t kDescentBatch = 16;
  void descendBatch(const OrbDescriptor* descriptors, size_t n, int depth, NodeId* leaf,
                    NodeId* at_depth) const;
  /// Children, depths and word numbering from node_parent_ (children must be contiguous
  /// ranges after their parent); empty when consistent, else what is wrong.
  std::string buildTopology();

  int branching_ = 0;
  int levels_ = 0;
  uint64_t training_images_ = 0;
  std::string description_;
  std::vector<uint32_t> node_parent_;  ///< root: kNoParent
  std::vector<OrbDescriptor> node_descriptor_;
  struct Children {
    uint32_t first = 0;  ///< id of the first child; the children are first .. first+count-1
    uint32_t count = 0;  ///< 0 for a leaf
  };
  std::vector<Children> children_;
  std::vector<uint8_t> node_depth_;
  std::vector<NodeId> word_node_;
  std::vector<WordId> node_word_;  ///< word of a leaf; kNoWord for inner nodes
  std::vector<double> word_weight_;
};

}  // namespace cblox
