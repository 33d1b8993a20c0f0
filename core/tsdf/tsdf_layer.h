#pragma once

#include <cstddef>
#include <cstdint>
#include <memory>
#include <vector>

#include <absl/container/flat_hash_map.h>
#include <Eigen/Core>

#include "core/tsdf/block.h"
#include "core/tsdf/block_index.h"
#include "core/tsdf/layer_config.h"

namespace cblox {

/// A sparse TSDF volume: blocks allocated on demand, kept in a flat open-addressing hash
/// map (absl::flat_hash_map) keyed by the packed block index. All positions are in the
/// layer's own frame (for a subvolume, its frame M).
///
/// Thread safety: const methods may run concurrently with each other. Allocation and
/// removal (allocateBlock, removeBlock, clear) must not run concurrently with anything
/// else on the same layer; integrators allocate in a single-threaded phase and then write
/// voxels of existing blocks in parallel (see Block for the voxel-level contract).
class TsdfLayer {
 public:
  using BlockMap = absl::flat_hash_map<uint64_t, std::unique_ptr<Block>>;

  /// Throws std::invalid_argument with LayerConfig::validate()'s message when invalid.
  explicit TsdfLayer(const LayerConfig& config);

  TsdfLayer(const TsdfLayer&) = delete;
  TsdfLayer& operator=(const TsdfLayer&) = delete;
  TsdfLayer(TsdfLayer&&) = default;
  TsdfLayer& operator=(TsdfLayer&&) = default;

  const LayerConfig& config() const { return config_; }
  float voxelSize() const { return config_.voxel_size; }
  float voxelSizeInv() const { return voxel_size_inv_; }
  int voxelsPerSide() const { return config_.voxels_per_side; }
  int voxelsPerSideLog2() const { return voxels_per_side_log2_; }
  float blockSize() const { return block_size_; }
  float blockSizeInv() const { return block_size_inv_; }

  /// nullptr when the block is not allocated.
  Block* getBlock(const BlockIndex& index);
  const Block* getBlock(const BlockIndex& index) const;
  /// Lookup by packed key (packGridIndex); nullptr when absent. For hot loops that
  /// already hold the key.
  Block* getBlockByKey(uint64_t key) {
    const auto it = blocks_.find(key);
    return it == blocks_.end() ? nullptr : it->second.get();
  }
  /// Returns the existing block or allocates a zeroed one. `newly_allocated` (optional)
  /// tells which. Throws std::out_of_range if the index is outside the packable range.
  Block* allocateBlock(const BlockIndex& index, bool* newly_allocated = nullptr);
  /// True when a block was removed.
  bool removeBlock(const BlockIndex& index);
  void clear() { blocks_.clear(); }

  size_t numBlocks() const { return blocks_.size(); }
  std::vector<BlockIndex> blockIndices() const;
  const BlockMap& blocks() const { return blocks_; }

  BlockIndex blockIndexFromPoint(const Eigen::Vector3f& point) const {
    return gridIndexFromPoint(point, block_size_inv_);
  }
  GlobalVoxelIndex globalVoxelIndexFromPoint(const Eigen::Vector3f& point) const {
    return gridIndexFromPoint(point, voxel_size_inv_);
  }
  /// Centre of a global voxel, metres.
  Eigen::Vector3f globalVoxelCenter(const GlobalVoxelIndex& index) const {
    return (index.cast<float>() + Eigen::Vector3f::Constant(0.5f)) * config_.voxel_size;
  }

  /// The voxel containing `point` (nearest-centre lookup), nullptr if its block is absent.
  const TsdfVoxel* getVoxelAtPoint(const Eigen::Vector3f& point) const;
  const TsdfVoxel* getVoxel(const GlobalVoxelIndex& index) const;
  TsdfVoxel* getVoxel(const GlobalVoxelIndex& index);

  /// A fresh epoch for Block::markVisited, one per integration call (1, 2, ...).
  /// Not thread-safe: called by the integrator before its threads start.
  uint64_t nextIntegrationEpoch() { return ++integration_epoch_; }

  /// Bytes held: blocks plus the hash map's slot array.
  size_t memoryBytes() const;

 private:
  LayerConfig config_;
  int voxels_per_side_log2_ = 0;
  float voxel_size_inv_ = 0.0f;
  float block_size_ = 0.0f;
  float block_size_inv_ = 0.0f;
  BlockMap blocks_;
  uint64_t integration_epoch_ = 0;
};

}  // namespace cblox
