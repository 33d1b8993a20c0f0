#pragma once

#include <algorithm>
#include <atomic>
#include <cstddef>
#include <cstdint>
#include <memory>

#include <Eigen/Core>

#include "core/tsdf/block_index.h"
#include "core/tsdf/spin_lock.h"
#include "core/tsdf/voxel.h"

namespace cblox {

/// A cube of voxels_per_side^3 TSDF voxels stored in one flat array, x fastest.
/// The block with index b covers [b, b+1) * block_size in its layer's frame; voxel (i,j,k)
/// has its centre at origin + (i+0.5, j+0.5, k+0.5) * voxel_size.
///
/// Thread safety: index/geometry accessors are immutable and thread-safe. Voxel access is
/// not synchronised: concurrent writers must hold lock() (the ray-casting integrators do),
/// or own the block exclusively (the projective integrator partitions blocks by thread).
/// The `updated` flag and the change count are atomic.
class Block {
 public:
  Block(const BlockIndex& index, int voxels_per_side, float voxel_size);

  const BlockIndex& index() const { return index_; }
  int voxelsPerSide() const { return voxels_per_side_; }
  int voxelsPerSideLog2() const { return voxels_per_side_log2_; }
  int numVoxels() const { return num_voxels_; }
  float voxelSize() const { return voxel_size_; }
  float blockSize() const { return voxel_size_ * static_cast<float>(voxels_per_side_); }
  /// Position of the block's minimum corner in the layer frame, metres.
  const Eigen::Vector3f& origin() const { return origin_; }

  /// Linear index of a local voxel index (each component in [0, voxels_per_side)).
  int linearIndex(const GridIndex& local) const {
    return local.x() +
           ((local.y() + (local.z() << voxels_per_side_log2_)) << voxels_per_side_log2_);
  }
  /// Inverse of linearIndex.
  GridIndex localIndex(int linear) const {
    const int mask = voxels_per_side_ - 1;
    return GridIndex(linear & mask, (linear >> voxels_per_side_log2_) & mask,
                     linear >> (2 * voxels_per_side_log2_));
  }
  /// Centre of a local voxel in the layer frame, metres.
  Eigen::Vector3f voxelCenter(const GridIndex& local) const {
    return origin_ + (local.cast<float>() + Eigen::Vector3f::Constant(0.5f)) * voxel_size_;
  }

  TsdfVoxel& voxel(int linear) { return voxels_[static_cast<size_t>(linear)]; }
  const TsdfVoxel& voxel(int linear) const { return voxels_[static_cast<size_t>(linear)]; }
  TsdfVoxel& voxel(const GridIndex& local) { return voxel(linearIndex(local)); }
  const TsdfVoxel& voxel(const GridIndex& local) const { return voxel(linearIndex(local)); }
  TsdfVoxel* voxels() { return voxels_.get(); }
  const TsdfVoxel* voxels() const { return voxels_.get(); }

  /// Lock for writers that share the block (see class comment).
  SpinLock& lock() const { return lock_; }

  /// Set by integrators when a voxel changed; cleared by whoever consumes the change
  /// (the incremental mesher).
  bool updated() const { return updated_.load(std::memory_order_acquire); }
  /// setUpdated(true) also advances changeCount().
  void setUpdated(bool value) {
    if (value) change_count_.fetch_add(1, std::memory_order_acq_rel);
    updated_.store(value, std::memory_order_release);
  }
  /// Number of setUpdated(true) calls so far. Unlike `updated`, nobody clears it, so any
  /// number of consumers (the mesher, the distance field) can each keep the count they last
  /// saw and tell whether the block changed since.
  uint64_t changeCount() const { return change_count_.load(std::memory_order_acquire); }

  /// Per-call scratch for integrators: one "visited" bit per voxel, valid for one
  /// integration epoch (TsdfLayer::nextIntegrationEpoch). Returns true when the voxel had
  /// not been visited in `epoch` yet (and marks it). Not thread-safe: hold lock().
  bool markVisited(int linear, uint64_t epoch) {
    if (visited_epoch_ != epoch) {
      if (!visited_bits_) visited_bits_.reset(new uint64_t[visitedWords()]);
      std::fill_n(visited_bits_.get(), visitedWords(), uint64_t{0});
      visited_epoch_ = epoch;
    }
    uint64_t& word = visited_bits_[static_cast<size_t>(linear) >> 6];
    const uint64_t bit = uint64_t{1} << (linear & 63);
    const bool fresh = (word & bit) == 0;
    word |= bit;
    return fresh;
  }

  /// Number of voxels with weight > 0 (O(voxels)).
  int countObservedVoxels() const;

  /// Bytes owned by this block (object + voxel array).
  size_t memoryBytes() const {
    return sizeof(Block) + static_cast<size_t>(num_voxels_) * sizeof(TsdfVoxel) +
           (visited_bits_ ? visitedWords() * sizeof(uint64_t) : 0);
  }

 private:
  BlockIndex index_;
  int voxels_per_side_;
  int voxels_per_side_log2_;
  int num_voxels_;
  float voxel_size_;
  Eigen::Vector3f origin_;
  std::unique_ptr<TsdfVoxel[]> voxels_;
  size_t visitedWords() const { return (static_cast<size_t>(num_voxels_) + 63) / 64; }

  mutable SpinLock lock_;
  uint64_t visited_epoch_ = 0;  // 0: never used (epochs start at 1)
  std::unique_ptr<uint64_t[]> visited_bits_;
  std::atomic<bool> updated_{false};
  std::atomic<uint64_t> change_count_{0};
};

}  // namespace cblox
