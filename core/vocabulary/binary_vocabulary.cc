#include "core/vocabulary/binary_vocabulary.h"

#include <algorithm>
#include <array>
#include <atomic>
#include <chrono>
#include <cmath>
#include <limits>
#include <random>
#include <stdexcept>
#include <thread>

#include "core/vocabulary/k_majority.h"

namespace cblox {
namespace {

/// A tree grown below one node: local node 0 is that node (its entries here are unused: the node
/// itself lives in the parent tree); every other node's parent is a local id.
struct Subtree {
  std::vector<uint32_t> parents{0};
  std::vector<OrbDescriptor> descriptors{OrbDescriptor{}};
  size_t splits = 0;
  size_t unconverged_splits = 0;
};

/// Grows a subtree by recursive k-majority splits of its root's members.
class SubtreeBuilder {
 public:
  SubtreeBuilder(const BinaryVocabularyConfig& config, uint64_t seed, Subtree* tree)
      : config_(config), rng_(seed), tree_(tree) {}

  void split(uint32_t node, std::vector<OrbDescriptor> members, int depth) {
    if (depth >= config_.levels || members.size() <= 1) return;
    const KMajorityResult clusters =
        kMajorityCluster(members, config_.branching, config_.max_iterations, rng_);
    ++tree_->splits;
    tree_->unconverged_splits += clusters.converged ? 0 : 1;
    if (clusters.centres.size() <= 1) return;  // does not split any further
    const auto first = static_cast<uint32_t>(tree_->parents.size());
    std::vector<std::vector<OrbDescriptor>> children(clusters.centres.size());
    for (size_t c = 0; c < clusters.centres.size(); ++c) {
      tree_->parents.push_back(node);
      tree_->descriptors.push_back(clusters.centres[c]);
    }
    for (size_t i = 0; i < members.size(); ++i) {
      children[clusters.assignment[i]].push_back(members[i]);
    }
    members = {};  // release before descending
    for (size_t c = 0; c < children.size(); ++c) {
      split(first + static_cast<uint32_t>(c), std::move(children[c]), depth + 1);
    }
  }

 private:
  const BinaryVocabularyConfig& config_;
  std::mt19937_64 rng_;
  Subtree* tree_;
};

/// splitmix64: independent seeds for the subtrees from the config's seed.
uint64_t mixSeed(uint64_t seed, uint64_t index) {
  uint64_t z = seed + 0x9e3779b97f4a7c15ull * (index + 1);
  z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ull;
  z = (z ^ (z >> 27)) * 0x94d049bb133111ebull;
  return z ^ (z >> 31);
}

/// Grows the subtrees of the root's children on `threads` threads (each child's subtree has
/// its own seeded generator, so the result does not depend on the thread count).
std::vector<Subtree> growSubtrees(const BinaryVocabularyConfig& config,
                                  std::vector<std::vector<OrbDescriptor>> members) {
  std::vector<Subtree> trees(members.size());
  std::atomic<size_t> next{0};
  auto work = [&] {
    for (size_t c = next++; c < trees.size(); c = next++) {
      SubtreeBuilder(config, mixSeed(config.seed, c), &trees[c]).split(0, std::move(members[c]), 1);
    }
  };
  std::vector<std::thread> threads;
  const size_t extra = std::min(trees.size(), static_cast<size_t>(config.num_threads)) - 1;
  for (size_t t = 0; t < extra; ++t) threads.emplace_back(work);
  work();
  for (std::thread& t : threads) t.join();
  return trees;
}

}  // namespace

std::string BinaryVocabularyConfig::validate() const {
  if (branching < 2 || branching > 64) {
    return "branching (k) must be in [2, 64], got " + std::to_string(branching);
  }
  if (levels < 1 || levels > 8) {
    return "levels (L) must be in [1, 8], got " + std::to_string(levels);
  }
  if (std::pow(static_cast<double>(branching), levels) > 2147483648.0) {
    return "branching^levels must be <= 2^31 (node ids are 32-bit), got " +
           std::to_string(branching) + "^" + std::to_string(levels);
  }
  if (max_iterations < 1) {
    return "max_iterations must be >= 1, got " + std::to_string(max_iterations);
  }
  if (num_threads < 1) return "num_threads must be >= 1, got " + std::to_string(num_threads);
  return "";
}

BinaryVocabulary BinaryVocabulary::train(const std::vector<std::vector<OrbDescriptor>>& images,
                                         const BinaryVocabularyConfig& config,
                                         const std::string& description,
                                         BinaryVocabularyTrainingStats* stats) {
  const auto start = std::chrono::steady_clock::now();
  if (const std::string error = config.validate(); !error.empty()) {
    throw std::invalid_argument("BinaryVocabularyConfig: " + error);
  }
  std::vector<OrbDescriptor> all;
  for (const auto& image : images) all.insert(all.end(), image.begin(), image.end());
  if (all.empty()) {
    throw std::invalid_argument("BinaryVocabulary::train: the training images have no descriptor");
  }
  BinaryVocabularyTrainingStats local;
  BinaryVocabularyTrainingStats& s = stats != nullptr ? *stats : local;
  s = BinaryVocabularyTrainingStats{};
  s.images = images.size();
  s.descriptors = all.size();

  BinaryVocabulary vocabulary;
  vocabulary.branching_ = config.branching;
  vocabulary.levels_ = config.levels;
  vocabulary.training_images_ = images.size();
  vocabulary.description_ = description;
  // The root is always split (even data that does not split gets one child), then the
  // children's subtrees grow in parallel and are spliced in child order: the root's children
  // are nodes 1..m, followed by the rest of child 0's subtree, of child 1's, ...
  std::mt19937_64 rng(config.seed);
  const KMajorityResult root = kMajorityCluster(all, config.branching, config.max_iterations, rng);
  s.splits = 1;
  s.unconverged_splits = root.converged ? 0 : 1;
  std::vector<std::vector<OrbDescriptor>> members(root.centres.size());
  for (size_t i = 0; i < all.size(); ++i) members[root.assignment[i]].push_back(all[i]);
  all = {};
  const std::vector<Subtree> subtrees = growSubtrees(config, std::move(members));
  vocabulary.node_parent_.assign(1 + root.centres.size(), 0);
  vocabulary.node_parent_[0] = kNoParent;
  vocabulary.node_descriptor_ = {OrbDescriptor{}};
  vocabulary.node_descriptor_.insert(vocabulary.node_descriptor_.end(), root.centres.begin(),
                                     root.centres.end());
  for (size_t c = 0; c < subtrees.size(); ++c) {
    const Subtree& tree = subtrees[c];
    // Local id 0 is child c (global 1 + c); local id j > 0 is global offset + j - 1.
    const auto offset = static_cast<uint32_t>(vocabulary.node_parent_.size());
    for (size_t j = 1; j < tree.parents.size(); ++j) {
      const uint32_t p = tree.parents[j];
      vocabulary.node_parent_.push_back(p == 0 ? static_cast<uint32_t>(1 + c) : offset + p - 1);
      vocabulary.node_descriptor_.push_back(tree.descriptors[j]);
    }
    s.splits += tree.splits;
    s.unconverged_splits += tree.unconverged_splits;
  }
  if (const std::string error = vocabulary.buildTopology(); !error.empty()) {
    throw std::logic_error("BinaryVocabulary::train built an inconsistent tree: " + error);
  }

  // idf: log(N / images with the word), as a lookup (not the clustering) assigns words.
  std::vector<uint32_t> images_with_word(vocabulary.wordCount(), 0);
  std::vector<uint64_t> last_image(vocabulary.wordCount(), std::numeric_limits<uint64_t>::max());
  for (size_t i = 0; i < images.size(); ++i) {
    for (const OrbDescriptor& d : images[i]) {
      const WordId w = vocabulary.wordOf(d);
      if (last_image[w] != i) {
        last_image[w] = i;
        ++images_with_word[w];
      }
    }
  }
  vocabulary.word_weight_.assign(vocabulary.wordCount(), 0.0);
  const double n = static_cast<double>(images.size());
  for (size_t w = 0; w < vocabulary.wordCount(); ++w) {
    if (images_with_word[w] > 0) vocabulary.word_weight_[w] = std::log(n / images_with_word[w]);
  }
  s.nodes = vocabulary.nodeCount();
  s.words = vocabulary.wordCount();
  s.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return vocabulary;
}

std::string BinaryVocabulary::buildTopology() {
  const size_t n = node_parent_.size();
  if (n == 0 || node_parent_[0] != kNoParent) return "node 0 is not the root";
  if (node_descriptor_.size() != n) return "descriptor count differs from node count";
  children_.assign(n, Children{});
  node_depth_.assign(n, 0);
  for (size_t i = 1; i < n; ++i) {
    const uint32_t p = node_parent_[i];
    if (p >= i) {
      return "node " + std::to_string(i) + " has parent " + std::to_string(p) +
             " (parents must precede their children)";
    }
    Children& c = children_[p];
    if (c.count == 0) {
      c.first = static_cast<uint32_t>(i);
    } else if (c.first + c.count != i) {
      return "the children of node " + std::to_string(p) + " are not contiguous";
    }
    ++c.count;
    if (c.count > static_cast<uint32_t>(branching_)) {
      return "node " + std::to_string(p) + " has more than k = " + std::to_string(branching_) +
             " children";
    }
    node_depth_[i] = static_cast<uint8_t>(node_depth_[p] + 1);
    if (node_depth_[i] > levels_) {
      return "node " + std::to_string(i) + " is deeper than L = " + std::to_string(levels_);
    }
  }
  if (children_[0].count == 0) return "the root has no children";
  word_node_.clear();
  node_word_.assign(n, kNoWord);
  for (size_t i = 1; i < n; ++i) {
    if (children_[i].count > 0) continue;
    node_word_[i] = static_cast<WordId>(word_node_.size());
    word_node_.push_back(static_cast<NodeId>(i));
  }
  return "";
}

NodeId BinaryVocabulary::descend(const OrbDescriptor& descriptor, int depth,
                                 NodeId* at_depth) const {
  NodeId leaf = 0, marked = 0;
  descendBatch(&descriptor, 1, depth, &leaf, &marked);
  if (at_depth != nullptr) *at_depth = marked;
  return leaf;
}

void BinaryVocabulary::descendBatch(const OrbDescriptor* descriptors, size_t n, int depth,
                                    NodeId* leaf, NodeId* at_depth) const {
  // The descents of the batch advance one level at a time, each step touching memory that the
  // previous level's pass asked the cache for: the next node's child range, then the children's
  // descriptors. A 22 MB vocabulary is mostly out of cache, so overlapping the misses of the
  // batch is what makes this faster than descending one descriptor after the other.
  constexpr int kLine = 64;
  const auto prefetchChildren = [&](NodeId node) {
    const Children& c = children_[node];
    const char* begin = reinterpret_cast<const char*>(&node_descriptor_[c.first]);
    const char* end = begin + static_cast<size_t>(c.count) * sizeof(OrbDescriptor);
    for (const char* p = begin; p < end; p += kLine) __builtin_prefetch(p);
  };
  std::array<NodeId, kDescentBatch> node{};
  std::array<bool, kDescentBatch> done{};
  for (size_t b = 0; b < n; ++b) at_depth[b] = 0;
  for (int level = 1;; ++level) {
    bool any = false;
    for (size_t b = 0; b < n; ++b) {
      if (done[b]) continue;
      if (children_[node[b]].count == 0) {
        done[b] = true;
        continue;
      }
      any = true;
      prefetchChildren(node[b]);
    }
    if (!any) break;
    for (size_t b = 0; b < n; ++b) {
      if (done[b]) continue;
      const Children& c = children_[node[b]];
      const uint32_t end = c.first + c.count;
      NodeId best = c.first;
      int best_distance = hammingDistance(descriptors[b], node_descriptor_[c.first]);
      for (uint32_t k = c.first + 1; k < end; ++k) {
        const int d = hammingDistance(descriptors[b], node_descriptor_[k]);
        if (d < best_distance) {
          best_distance = d;
          best = k;
        }
      }
      node[b] = best;
      if (level <= depth) at_depth[b] = best;
      __builtin_prefetch(&children_[best]);
    }
  }
  for (size_t b = 0; b < n; ++b) {
    leaf[b] = node[b];
    __builtin_prefetch(&node_word_[node[b]]);
  }
}

WordId BinaryVocabulary::wordOf(const OrbDescriptor& descriptor) const {
  return node_word_[descend(descriptor, 0, nullptr)];
}

const OrbDescriptor& BinaryVocabulary::wordDescriptor(WordId word) const {
  return node_descriptor_[word_node_[word]];
}

BowVector BinaryVocabulary::transform(const std::vector<OrbDescriptor>& features) const {
  BowVector bow;
  transform(features, &bow, nullptr);
  return bow;
}

void BinaryVocabulary::transform(const std::vector<OrbDescriptor>& features, BowVector* bow,
                                 FeatureVector* feature_vector, int levels_up) const {
  const int depth = std::max(0, levels_ - std::max(0, levels_up));
  std::vector<std::pair<WordId, double>> words;
  std::vector<std::pair<NodeId, uint32_t>> nodes;
  words.reserve(features.size());
  if (feature_vector != nullptr) nodes.reserve(features.size());
  std::array<NodeId, kDescentBatch> leaf, at_depth;
  for (size_t i0 = 0; i0 < features.size(); i0 += kDescentBatch) {
    const size_t n = std::min(kDescentBatch, features.size() - i0);
    descendBatch(&features[i0], n, depth, leaf.data(), at_depth.data());
    for (size_t b = 0; b < n; ++b) {
      const WordId w = node_word_[leaf[b]];
      if (feature_vector != nullptr) nodes.emplace_back(at_depth[b], static_cast<uint32_t>(i0 + b));
      if (word_weight_[w] > 0.0) words.emplace_back(w, word_weight_[w]);
    }
  }
  if (bow != nullptr) {
    bow->clear();
    std::sort(words.begin(), words.end());
    double total = 0.0;
    for (const auto& [w, weight] : words) {
      total += weight;
      if (!bow->empty() && bow->back().first == w) {
        bow->back().second += weight;
      } else {
        bow->emplace_back(w, weight);
      }
    }
    for (auto& entry : *bow) entry.second /= total;
  }
  if (feature_vector != nullptr) {
    feature_vector->clear();
    std::sort(nodes.begin(), nodes.end());
    for (const auto& [node, index] : nodes) {
      if (feature_vector->empty() || feature_vector->back().first != node) {
        feature_vector->emplace_back(node, std::vector<uint32_t>{});
      }
      feature_vector->back().second.push_back(index);
    }
  }
}

}  // namespace cblox
