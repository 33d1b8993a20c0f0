#pragma once

#include <cstdint>
#include <random>
#include <vector>

#include "core/features/orb_descriptor.h"

namespace cblox {

/// Bitwise majority vote over binary descriptors, accumulated one descriptor at a time with
/// bit-sliced counters (a ripple-carry add over 64 bit positions at once, amortised two word
/// operations per 64 bits), so a centroid of n descriptors costs O(n) word operations instead
/// of O(256 n) bit operations. Not thread-safe (mutable accumulator); one per thread.
class BitMajority {
 public:
  void add(const OrbDescriptor& d);
  /// Descriptors added so far.
  uint64_t count() const { return count_; }
  /// Bit i is set iff more than half of the added descriptors have bit i set (a tie gives 0);
  /// all zero when nothing was added.
  OrbDescriptor majority() const;
  void clear();

 private:
  static constexpr int kPlanes = 40;  ///< counts up to 2^40 descriptors
  uint64_t planes_[4][kPlanes] = {};  ///< planes_[w][p]: bit p of the count of each bit of word w
  int used_planes_ = 0;
  uint64_t count_ = 0;
};

/// Result of k-majority clustering of n descriptors.
struct KMajorityResult {
  /// Centroids of the non-empty clusters (at most k; fewer when the data has fewer distinct
  /// descriptors or a cluster emptied): the bitwise majority of the members when converged
  /// (of the previous pass's members when stopped by the iteration limit).
  std::vector<OrbDescriptor> centres;
  /// For every input descriptor, the index of its nearest centre (Hamming distance; ties go
  /// to the lowest index), so routing a descriptor down a tree of these centres puts it in
  /// the same cluster as during training.
  std::vector<uint32_t> assignment;
  int iterations = 0;      ///< assignment passes made
  bool converged = false;  ///< assignments stopped changing before max_iterations
};

/// k-majority clustering (Grana et al. 2013; DBoW2's binary k-means): greedy k-means++
/// seeding with the Hamming distance (the first centre uniform, each next one the best of
/// 2 + floor(ln k) candidates drawn with probability proportional to the squared distance to
/// the nearest chosen centre; seeding stops early when every descriptor coincides with a
/// centre), then Lloyd iterations with the bitwise
/// majority as centroid until no assignment changes or `max_iterations` passes were made. A
/// cluster that loses all its members is moved onto the descriptor farthest from its centre
/// (so two seeds in one natural cluster do not cost a cluster).
/// If it stopped on the iteration limit, the centres are recomputed from the last assignment
/// and the descriptors reassigned once more, so `assignment` always is nearest-centre.
/// Deterministic for a given rng state (uses only the rng's raw 64-bit output).
/// Cost O(n k (iterations + 2 + ln k)) distances. Throws std::invalid_argument for k < 1 or
/// max_iterations < 1. Thread-safe for distinct rngs (pure otherwise).
KMajorityResult kMajorityCluster(const std::vector<OrbDescriptor>& descriptors, int k,
                                 int max_iterations, std::mt19937_64& rng);

}  // namespace cblox
