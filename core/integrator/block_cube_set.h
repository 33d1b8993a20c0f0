#pragma once

#include <atomic>
#include <cstddef>
#include <cstdint>
#include <memory>

#include "core/tsdf/block_index.h"

namespace cblox {

/// An exact set of the block indices inside one cube of blocks, one bit each, for "was this
/// block already found in this frame?" where a frame's blocks all lie near the sensor (the
/// projective integrator's block search). Cheaper than a hash set: a test is an index
/// computation and one load.
///
/// - reset() places the cube (`centre` +- `half_side` blocks per axis) and empties it; it
///   returns false, and the set is unusable until the next reset, when the cube would hold
///   more than max_bits blocks.
/// - covers(lo, hi) says whether the box [lo, hi] lies inside the cube; contains() and
///   insert() take only indices inside it (callers check covers() per box).
/// - run() reads up to 64 consecutive bits at once (a row of blocks along x).
/// - insert() is an atomic fetch-or: two threads inserting the same block get exactly one
///   `true`.
///
/// Thread safety: covers(), contains(), run() and insert() are thread-safe; reset() must not run
/// concurrently with them.
class BlockCubeSet {
 public:
  /// `max_bits`: the largest cube reset() accepts (memory: max_bits / 8 bytes).
  explicit BlockCubeSet(size_t max_bits) : max_bits_(max_bits) {}

  bool reset(const BlockIndex& centre, int half_side) {
    valid_ = false;
    if (half_side < 0) return false;
    const uint64_t side = 2 * static_cast<uint64_t>(half_side) + 1;
    const uint64_t bits = side * side * side;
    if (bits > max_bits_) return false;
    const size_t words = static_cast<size_t>((bits + 63) / 64);
    if (words > capacity_words_) {
      words_.reset(new std::atomic<uint64_t>[words]);
      capacity_words_ = words;
    }
    for (size_t i = 0; i < words; ++i) words_[i].store(0, std::memory_order_relaxed);
    lo_ = centre - GridIndex::Constant(half_side);
    side_ = static_cast<int>(side);
    valid_ = true;
    return true;
  }

  /// True when the set is usable and every index of the box [lo, hi] is inside the cube.
  bool covers(const BlockIndex& lo, const BlockIndex& hi) const {
    if (!valid_) return false;
    for (int axis = 0; axis < 3; ++axis) {
      if (lo[axis] < lo_[axis] || hi[axis] >= lo_[axis] + side_) return false;
    }
    return true;
  }

  /// Blocks per side of the cube: bitOf(x, y + 1, z) = bitOf(x, y, z) + side(), and
  /// bitOf(x, y, z + 1) = bitOf(x, y, z) + side()^2.
  size_t side() const { return static_cast<size_t>(side_); }
  /// The bit of block (x, y, z), which must be inside the cube.
  size_t bitOf(int x, int y, int z) const {
    return (static_cast<size_t>(z - lo_.z()) * static_cast<size_t>(side_) +
            static_cast<size_t>(y - lo_.y())) *
               static_cast<size_t>(side_) +
           static_cast<size_t>(x - lo_.x());
  }
  bool contains(size_t bit) const {
    return (words_[bit >> 6].load(std::memory_order_relaxed) >> (bit & 63)) & 1u;
  }
  /// The `n` (1..64) consecutive bits from `bit` on, the last of which must be inside the
  /// cube, as a word: its bit i is set when bit + i is in the set. A block row along x is
  /// consecutive bits, so this reads up to 64 blocks of a row in one or two loads.
  uint64_t run(size_t bit, int n) const {
    const size_t word = bit >> 6;
    const unsigned offset = static_cast<unsigned>(bit & 63);
    uint64_t bits = words_[word].load(std::memory_order_relaxed) >> offset;
    if (offset + static_cast<unsigned>(n) > 64) {  // offset > 0 here
      bits |= words_[word + 1].load(std::memory_order_relaxed) << (64 - offset);
    }
    return n == 64 ? bits : bits & ((uint64_t{1} << n) - 1);
  }
  /// True when the block was not in the set (it is now).
  bool insert(size_t bit) {
    const uint64_t mask = uint64_t{1} << (bit & 63);
    return (words_[bit >> 6].fetch_or(mask, std::memory_order_relaxed) & mask) == 0;
  }

 private:
  size_t max_bits_;
  std::unique_ptr<std::atomic<uint64_t>[]> words_;
  size_t capacity_words_ = 0;
  BlockIndex lo_ = BlockIndex::Zero();
  int side_ = 0;
  bool valid_ = false;
};

}  // namespace cblox
