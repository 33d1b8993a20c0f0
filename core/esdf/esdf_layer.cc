#include "core/esdf/esdf_layer.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

namespace cblox {

EsdfLayer::EsdfLayer(const LayerConfig& config, float max_distance_m)
    : config_(config), max_distance_m_(max_distance_m) {
  if (const std::string e = config.validate(); !e.empty()) throw std::invalid_argument(e);
  if (!std::isfinite(max_distance_m) || !(max_distance_m > 0.0f)) {
    throw std::invalid_argument("max_distance_m must be finite and > 0");
  }
  while ((1 << voxels_per_side_log2_) < config.voxels_per_side) ++voxels_per_side_log2_;
  voxels_per_block_ = config.voxels_per_side * config.voxels_per_side * config.voxels_per_side;
  voxel_size_inv_ = 1.0f / config.voxel_size;
}

EsdfBlock* EsdfLayer::getBlock(const BlockIndex& index) {
  if (!gridIndexInRange(index)) return nullptr;
  const auto it = blocks_.find(packGridIndex(index));
  return it == blocks_.end() ? nullptr : it->second.get();
}

const EsdfBlock* EsdfLayer::getBlock(const BlockIndex& index) const {
  if (!gridIndexInRange(index)) return nullptr;
  const auto it = blocks_.find(packGridIndex(index));
  return it == blocks_.end() ? nullptr : it->second.get();
}

EsdfBlock* EsdfLayer::allocateBlock(const BlockIndex& index, bool* newly_allocated) {
  if (!gridIndexInRange(index)) throw std::out_of_range("block index outside the packed range");
  auto& slot = blocks_[packGridIndex(index)];
  if (newly_allocated != nullptr) *newly_allocated = (slot == nullptr);
  if (!slot) {
    slot = std::make_unique<EsdfBlock>(index, voxels_per_block_);
    EsdfBlock* block = slot.get();
    EsdfVoxel* voxels = block->mutableVoxels();
    for (int i = 0; i < voxels_per_block_; ++i) voxels[i].own_distance = max_distance_m_;
    link(block, block);
    return block;
  }
  return slot.get();
}

void EsdfLayer::link(EsdfBlock* block, EsdfBlock* target) {
  for (int dz = -1; dz <= 1; ++dz) {
    for (int dy = -1; dy <= 1; ++dy) {
      for (int dx = -1; dx <= 1; ++dx) {
        const BlockIndex other_index = block->index + BlockIndex(dx, dy, dz);
        EsdfBlock* other = (dx == 0 && dy == 0 && dz == 0) ? block : getBlock(other_index);
        block->neighbours[static_cast<size_t>(EsdfBlock::neighbourSlot(dx, dy, dz))] =
            target == nullptr && other == block ? nullptr : other;
        if (other != nullptr && other != block) {
          other->neighbours[static_cast<size_t>(EsdfBlock::neighbourSlot(-dx, -dy, -dz))] = target;
        }
      }
    }
  }
}

bool EsdfLayer::removeBlock(const BlockIndex& index) {
  EsdfBlock* block = getBlock(index);
  if (block == nullptr) return false;
  link(block, nullptr);
  return blocks_.erase(packGridIndex(index)) > 0;
}

const EsdfVoxel* EsdfLayer::getVoxel(const GlobalVoxelIndex& index) const {
  BlockIndex block;
  GridIndex local;
  splitGlobalVoxelIndex(index, voxels_per_side_log2_, &block, &local);
  const EsdfBlock* b = getBlock(block);
  return b == nullptr ? nullptr : &b->voxel(linearIndex(local));
}

EsdfVoxel* EsdfLayer::getVoxel(const GlobalVoxelIndex& index) {
  BlockIndex block;
  GridIndex local;
  splitGlobalVoxelIndex(index, voxels_per_side_log2_, &block, &local);
  EsdfBlock* b = getBlock(block);
  return b == nullptr ? nullptr : &b->mutableVoxels()[linearIndex(local)];
}

void EsdfBlock::unshare() {
  std::shared_ptr<EsdfVoxel[]> copy(new EsdfVoxel[static_cast<size_t>(num_voxels_)]);
  std::copy(voxels_.get(), voxels_.get() + num_voxels_, copy.get());
  voxels_ = std::move(copy);
  shared_ = false;
}

std::shared_ptr<const EsdfLayer> EsdfLayer::snapshot() {
  auto copy = std::make_shared<EsdfLayer>(config_, max_distance_m_);
  copy->is_snapshot_ = true;
  copy->blocks_.reserve(blocks_.size());
  for (auto& [key, block] : blocks_) {
    auto& slot = copy->blocks_[key];
    slot = std::make_unique<EsdfBlock>(*block);  // shares voxels_
    slot->shared_ = true;
    slot->copy_ = nullptr;
    block->shared_ = true;
    block->copy_ = slot.get();
  }
  for (auto& [key, block] : blocks_) {
    EsdfBlock* target = block->copy_;
    for (size_t i = 0; i < block->neighbours.size(); ++i) {
      const EsdfBlock* n = block->neighbours[i];
      target->neighbours[i] = n == nullptr ? nullptr : n->copy_;
    }
  }
  for (auto& [key, block] : blocks_) block->copy_ = nullptr;
  return copy;
}

size_t EsdfLayer::memoryBytes() const {
  const size_t per_block = is_snapshot_ ? sizeof(EsdfBlock) : bytesPerBlock();
  return sizeof(EsdfLayer) + blocks_.size() * per_block +
         blocks_.capacity() * (sizeof(BlockMap::value_type) + 1);
}

}  // namespace cblox
