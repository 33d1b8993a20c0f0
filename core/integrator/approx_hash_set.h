#pragma once

#include <atomic>
#include <cstdint>
#include <memory>

#include "core/tsdf/block_index.h"

namespace cblox {

/// A fixed-size, one-element-per-bucket, lock-free set of 64-bit keys, as used by the
/// fast integrator for "was this cell already used in this frame?".
///
/// - insert() is an atomic compare-and-swap on one bucket: two threads inserting the
///   same key get exactly one `true`.
/// - It is approximate in one direction only: a key can be forgotten when another key
///   hashing to the same bucket replaces it (insert then returns true again). It never
///   reports a key that was not inserted since the last clear(): the bucket (low hash
///   bits) plus the 48-bit fingerprint (high hash bits) hold all 64 bits of a bijective
///   hash when there are >= 2^16 buckets.
/// - clear() is O(1): each bucket stores a 16-bit epoch; entries of older epochs read as
///   empty. Only every 65535th clear() touches the array.
///
/// Thread safety: insert() is thread-safe; clear() must not run concurrently with insert().
class ApproxHashSet {
 public:
  /// `log2_buckets` in [16, 30].
  explicit ApproxHashSet(int log2_buckets)
      : mask_((uint64_t{1} << log2_buckets) - 1), buckets_(new std::atomic<uint64_t>[mask_ + 1]) {
    for (uint64_t i = 0; i <= mask_; ++i) buckets_[i].store(0, std::memory_order_relaxed);
  }

  /// True when `key` was not in the set (it is now); false when it already was.
  bool insert(uint64_t key) {
    const uint64_t hash = mixHash(key);
    const uint64_t entry = entryOf(hash);
    std::atomic<uint64_t>& bucket = buckets_[hash & mask_];
    uint64_t current = bucket.load(std::memory_order_relaxed);
    while (current != entry) {
      if (bucket.compare_exchange_weak(current, entry, std::memory_order_relaxed)) return true;
    }
    return false;
  }

  /// True when `key` is in the set (inserted since the last clear() and not forgotten).
  /// Thread-safe; a concurrent insert of the same key may or may not be seen.
  bool contains(uint64_t key) const {
    const uint64_t hash = mixHash(key);
    const uint64_t entry = entryOf(hash);
    return buckets_[hash & mask_].load(std::memory_order_relaxed) == entry;
  }
  /// The same set semantics for keys made of a cluster key and a member index in
  /// [0, 2^member_bits): the members of one cluster (e.g. the voxels of one block) occupy
  /// consecutive buckets, so spatially coherent queries stay in cache. Identity: the
  /// bucket holds the member and the low (log2_buckets - member_bits) bits of the
  /// cluster's bijective hash, the entry its top 48 bits; two different keys can only be
  /// confused if their cluster hashes agree on all of those (>= 59 of 64 bits for the
  /// integrators' settings). `member_bits` < log2_buckets.
  bool insertInCluster(uint64_t cluster_key, uint32_t member, int member_bits) {
    const uint64_t hash = mixHash(cluster_key);
    const uint64_t entry = entryOf(hash);
    std::atomic<uint64_t>& bucket = buckets_[((hash << member_bits) | member) & mask_];
    uint64_t current = bucket.load(std::memory_order_relaxed);
    while (current != entry) {
      if (bucket.compare_exchange_weak(current, entry, std::memory_order_relaxed)) return true;
    }
    return false;
  }

  /// Hints the CPU to fetch the bucket insertInCluster(cluster_key, member, member_bits)
  /// will touch, so a batch of lookups can overlap their cache misses. Thread-safe.
  void prefetchInCluster(uint64_t cluster_key, uint32_t member, int member_bits) const {
    const uint64_t hash = mixHash(cluster_key);
    __builtin_prefetch(&buckets_[((hash << member_bits) | member) & mask_], 1);
  }

  /// Empties the set.
  void clear() {
    if (++epoch_ == (uint64_t{1} << (64 - kFingerprintBits))) {
      for (uint64_t i = 0; i <= mask_; ++i) buckets_[i].store(0, std::memory_order_relaxed);
      epoch_ = 1;
    }
  }

  size_t numBuckets() const { return mask_ + 1; }
  size_t memoryBytes() const { return numBuckets() * sizeof(uint64_t); }

 private:
  static constexpr int kFingerprintBits = 48;
  // What a bucket holds for a key of hash `hash` in the current epoch.
  uint64_t entryOf(uint64_t hash) const {
    return (epoch_ << kFingerprintBits) | (hash >> (64 - kFingerprintBits));
  }
  uint64_t mask_;
  std::unique_ptr<std::atomic<uint64_t>[]> buckets_;
  uint64_t epoch_ = 1;  // 0 marks a never-written bucket
};

}  // namespace cblox
