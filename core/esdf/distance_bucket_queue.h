#pragma once

#include <cstddef>
#include <cstdint>
#include <type_traits>
#include <utility>
#include <vector>

namespace cblox {

/// A bucket priority queue keyed by a small non-negative integer (a distance in fractions of
/// a voxel). push is O(1); pop returns an entry of the smallest key present and costs O(1)
/// amortised plus the empty buckets it skips. Keys larger than the bound given at
/// construction are refused by the caller's contract (checked: they are clamped into the
/// last bucket, which keeps the queue's ordering valid for all smaller keys).
///
/// Memory: each bucket is a stack of fixed-size chunks drawn from one free list that the
/// queue shares among its buckets, and a chunk a pop empties goes back to it at once. So a
/// wave that moves through the keys reuses the chunks of the buckets it has passed, and the
/// storage follows the entries held at once (at most one partly filled chunk per bucket
/// more), not the entries ever pushed. Storage stays allocated until releaseStorage() or
/// destruction. Not thread-safe.
template <typename Entry>
class DistanceBucketQueue {
  static_assert(std::is_trivially_copyable_v<Entry>, "entries are copied as bytes");

 public:
  /// Entries per chunk.
  static constexpr size_t kChunkEntries = 128;

  explicit DistanceBucketQueue(uint32_t max_key) : heads_(static_cast<size_t>(max_key) + 1) {}
  DistanceBucketQueue(const DistanceBucketQueue&) = delete;
  DistanceBucketQueue& operator=(const DistanceBucketQueue&) = delete;
  DistanceBucketQueue(DistanceBucketQueue&& other) noexcept { swap(other); }
  DistanceBucketQueue& operator=(DistanceBucketQueue&& other) noexcept {
    DistanceBucketQueue(std::move(other)).swap(*this);
    return *this;
  }
  ~DistanceBucketQueue() {
    for (Chunk* head : heads_) freeChain(head);
    freeChain(free_);
  }

  bool empty() const { return size_ == 0; }
  size_t size() const { return size_; }

  void push(uint32_t key, const Entry& entry) {
    if (key >= heads_.size()) key = static_cast<uint32_t>(heads_.size() - 1);
    Chunk*& head = heads_[key];
    if (head == nullptr || head->count == kChunkEntries) {
      Chunk* chunk = takeChunk();
      chunk->next = head;
      head = chunk;
    }
    head->entries[head->count++] = entry;
    if (key < lowest_) lowest_ = key;
    if (++size_ > peak_size_) peak_size_ = size_;
  }

  /// Removes an entry of the smallest key into *entry and *key. Precondition: !empty().
  void pop(Entry* entry, uint32_t* key) {
    while (heads_[lowest_] == nullptr) ++lowest_;
    Chunk*& head = heads_[lowest_];
    *entry = head->entries[--head->count];
    *key = lowest_;
    if (head->count == 0) {  // back to the free list for the buckets still to come
      Chunk* empty_chunk = head;
      head = empty_chunk->next;
      empty_chunk->next = free_;
      free_ = empty_chunk;
    }
    --size_;
  }

  /// The most entries held at once, and the most bytes of chunks allocated at once, since
  /// construction or the last resetPeak().
  size_t peakSize() const { return peak_size_; }
  size_t peakStorageBytes() const { return peak_chunks_ * sizeof(Chunk); }
  void resetPeak() {
    peak_size_ = size_;
    peak_chunks_ = chunks_;
  }

  /// Entries the allocated chunks hold room for. O(1).
  size_t capacity() const { return chunks_ * kChunkEntries; }

  /// Frees the free chunks beyond room for `max_entries` entries, so that a large wave's
  /// peak does not stay allocated between waves. Precondition: empty() (every chunk is free
  /// then).
  void releaseStorage(size_t max_entries) {
    const size_t keep = (max_entries + kChunkEntries - 1) / kChunkEntries;
    while (chunks_ > keep && free_ != nullptr) {
      Chunk* chunk = free_;
      free_ = chunk->next;
      delete chunk;
      --chunks_;
    }
    lowest_ = 0;
  }

 private:
  struct Chunk {
    Chunk* next = nullptr;
    size_t count = 0;
    Entry entries[kChunkEntries];
  };

  Chunk* takeChunk() {
    if (free_ == nullptr) {
      if (++chunks_ > peak_chunks_) peak_chunks_ = chunks_;
      return new Chunk;
    }
    Chunk* chunk = free_;
    free_ = chunk->next;
    chunk->next = nullptr;
    chunk->count = 0;
    return chunk;
  }
  static void freeChain(Chunk* chunk) {
    while (chunk != nullptr) {
      Chunk* next = chunk->next;
      delete chunk;
      chunk = next;
    }
  }
  void swap(DistanceBucketQueue& other) noexcept {
    heads_.swap(other.heads_);
    std::swap(free_, other.free_);
    std::swap(chunks_, other.chunks_);
    std::swap(lowest_, other.lowest_);
    std::swap(size_, other.size_);
    std::swap(peak_size_, other.peak_size_);
    std::swap(peak_chunks_, other.peak_chunks_);
  }

  std::vector<Chunk*> heads_;  // per key: its newest chunk (null when the bucket is empty)
  Chunk* free_ = nullptr;      // empty chunks
  size_t chunks_ = 0;          // allocated, in buckets or free
  size_t peak_chunks_ = 0;
  uint32_t lowest_ = 0;
  size_t size_ = 0;
  size_t peak_size_ = 0;
};

}  // namespace cblox
