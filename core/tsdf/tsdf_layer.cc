#include "core/tsdf/tsdf_layer.h"

#include <bit>
#include <sstream>
#include <stdexcept>

namespace cblox {

TsdfLayer::TsdfLayer(const LayerConfig& config) : config_(config) {
  const std::string error = config.validate();
  if (!error.empty()) throw std::invalid_argument("LayerConfig: " + error);
  voxels_per_side_log2_ = std::countr_zero(static_cast<unsigned>(config.voxels_per_side));
  voxel_size_inv_ = 1.0f / config.voxel_size;
  block_size_ = config.voxel_size * static_cast<float>(config.voxels_per_side);
  block_size_inv_ = 1.0f / block_size_;
}

Block* TsdfLayer::getBlock(const BlockIndex& index) {
  if (!gridIndexInRange(index)) return nullptr;
  const auto it = blocks_.find(packGridIndex(index));
  return it == blocks_.end() ? nullptr : it->second.get();
}

const Block* TsdfLayer::getBlock(const BlockIndex& index) const {
  if (!gridIndexInRange(index)) return nullptr;
  const auto it = blocks_.find(packGridIndex(index));
  return it == blocks_.end() ? nullptr : it->second.get();
}

Block* TsdfLayer::allocateBlock(const BlockIndex& index, bool* newly_allocated) {
  if (!gridIndexInRange(index)) {
    std::ostringstream msg;
    msg << "block index (" << index.transpose() << ") is outside the packable range ["
        << kGridIndexMin << ", " << kGridIndexMax << "]";
    throw std::out_of_range(msg.str());
  }
  auto [it, inserted] = blocks_.try_emplace(packGridIndex(index));
  if (inserted) {
    it->second = std::make_unique<Block>(index, config_.voxels_per_side, config_.voxel_size);
  }
  if (newly_allocated != nullptr) *newly_allocated = inserted;
  return it->second.get();
}

bool TsdfLayer::removeBlock(const BlockIndex& index) {
  if (!gridIndexInRange(index)) return false;
  return blocks_.erase(packGridIndex(index)) > 0;
}

std::vector<BlockIndex> TsdfLayer::blockIndices() const {
  std::vector<BlockIndex> indices;
  indices.reserve(blocks_.size());
  for (const auto& [key, block] : blocks_) indices.push_back(block->index());
  return indices;
}

const TsdfVoxel* TsdfLayer::getVoxelAtPoint(const Eigen::Vector3f& point) const {
  return getVoxel(globalVoxelIndexFromPoint(point));
}

const TsdfVoxel* TsdfLayer::getVoxel(const GlobalVoxelIndex& index) const {
  BlockIndex block_index;
  GridIndex local;
  splitGlobalVoxelIndex(index, voxels_per_side_log2_, &block_index, &local);
  const Block* block = getBlock(block_index);
  return block == nullptr ? nullptr : &block->voxel(local);
}

TsdfVoxel* TsdfLayer::getVoxel(const GlobalVoxelIndex& index) {
  BlockIndex block_index;
  GridIndex local;
  splitGlobalVoxelIndex(index, voxels_per_side_log2_, &block_index, &local);
  Block* block = getBlock(block_index);
  return block == nullptr ? nullptr : &block->voxel(local);
}

size_t TsdfLayer::memoryBytes() const {
  size_t bytes = sizeof(TsdfLayer) + blocks_.capacity() * (sizeof(BlockMap::value_type) + 1);
  for (const auto& [key, block] : blocks_) bytes += block->memoryBytes();
  return bytes;
}

}  // namespace cblox
