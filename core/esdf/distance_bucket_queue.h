#pragma once

#include <cstddef>
#include <cstdint>
#include <vector>

namespace cblox {

/// A bucket priority queue keyed by a small non-negative integer (a distance in fractions of
/// a voxel). push is O(1); pop returns an entry of the smallest key present and costs O(1)
/// amortised plus the empty buckets it skips. Keys larger than the bound given at
/// construction are refused by the caller's contract (checked: they are clamped into the
/// last bucket, which keeps the queue's ordering valid for all smaller keys).
/// Not thread-safe.
template <typename Entry>
class DistanceBucketQueue {
 public:
  explicit DistanceBucketQueue(uint32_t max_key) : buckets_(static_cast<size_t>(max_key) + 1) {}

  bool empty() const { return size_ == 0; }
  size_t size() const { return size_; }

  void push(uint32_t key, const Entry& entry) {
    if (key >= buckets_.size()) key = static_cast<uint32_t>(buckets_.size() - 1);
    buckets_[key].push_back(entry);
    if (key < lowest_) lowest_ = key;
    ++size_;
  }

  /// Frees the storage of buckets that hold more than `keep_entries` entries' worth while
  /// empty (a large wave's peak), so that it does not stay allocated between waves.
  /// Precondition: empty().
  void releaseLargeBuckets(size_t keep_entries) {
    for (std::vector<Entry>& bucket : buckets_) {
      if (bucket.capacity() > keep_entries) std::vector<Entry>().swap(bucket);
    }
    lowest_ = 0;
  }

  /// Removes an entry of the smallest key into *entry and *key. Precondition: !empty().
  void pop(Entry* entry, uint32_t* key) {
    while (buckets_[lowest_].empty()) ++lowest_;
    *entry = buckets_[lowest_].back();
    *key = lowest_;
    buckets_[lowest_].pop_back();
    --size_;
  }

 private:
  std::vector<std::vector<Entry>> buckets_;
  uint32_t lowest_ = 0;
  size_t size_ = 0;
};

}  // namespace cblox
