#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <memory>

#include <absl/container/flat_hash_map.h>
#include <Eigen/Core>

#include "core/esdf/esdf_voxel.h"
#include "core/tsdf/block.h"
#include "core/tsdf/block_index.h"
#include "core/tsdf/layer_config.h"

namespace cblox {

/// The distance-field voxels of one TSDF block, on the same grid: voxel (i,j,k) of an
/// EsdfBlock is voxel (i,j,k) of the TSDF block with the same index.
///
/// The voxels are copy-on-write: EsdfLayer::snapshot() shares them with a read-only copy
/// of the layer, and the next mutableVoxels() of a shared block copies them first, so that
/// the snapshot never sees a write.
class EsdfBlock {
 public:
  EsdfBlock(const BlockIndex& block_index, int num_voxels)
      : index(block_index),
        voxels_(new EsdfVoxel[static_cast<size_t>(num_voxels)]),
        num_voxels_(num_voxels) {
    neighbours.fill(nullptr);
  }

  /// Index into `neighbours` of the block at offset (dx, dy, dz), each in {-1, 0, 1}.
  static int neighbourSlot(int dx, int dy, int dz) {
    return (dx + 1) + 3 * (dy + 1) + 9 * (dz + 1);
  }

  /// The voxels, x fastest (EsdfLayer::linearIndex).
  const EsdfVoxel* voxels() const { return voxels_.get(); }
  const EsdfVoxel& voxel(int linear) const { return voxels_[static_cast<size_t>(linear)]; }
  /// The voxels for writing: a private copy first when a snapshot shares them. The pointer
  /// stays valid until the next EsdfLayer::snapshot().
  EsdfVoxel* mutableVoxels() {
    if (shared_) [[unlikely]]
      unshare();
    return voxels_.get();
  }

  /// A block of the band around the TSDF's blocks: every voxel unknown, only carrying
  /// distances to obstacles of neighbouring blocks.
  bool isBand() const { return tsdf == nullptr; }

  BlockIndex index;
  /// The 26 adjacent blocks of the layer (null where absent; slot 13 is this block), kept
  /// by EsdfLayer::allocateBlock / removeBlock so that wavefronts cross block borders
  /// without a hash lookup.
  std::array<EsdfBlock*, 27> neighbours;
  /// The TSDF block this block was last computed from, and its Block::changeCount() then;
  /// null for a band block (EsdfConfig::band_blocks), which no TSDF block covers.
  const Block* tsdf = nullptr;
  uint64_t tsdf_change_count = 0;
  /// The EsdfIntegrator's number for this block during one update (its waves' queue names
  /// blocks by it).
  uint32_t queue_slot = 0;

 private:
  friend class EsdfLayer;
  void unshare();

  std::shared_ptr<EsdfVoxel[]> voxels_;
  int num_voxels_ = 0;
  bool shared_ = false;        // a snapshot holds voxels_
  EsdfBlock* copy_ = nullptr;  // scratch of EsdfLayer::snapshot(): this block's copy
};

/// A sparse distance field with the geometry (voxel size, block size, frame) of the TSDF
/// layer it is computed from: one EsdfBlock per TSDF block, and the band blocks around them.
///
/// Thread safety: const methods may run concurrently with each other; anything else needs
/// exclusive access (the owner's lock). A snapshot() is immutable and shares nothing
/// writable with its source: readers use it without any lock while the source is updated.
class EsdfLayer {
 public:
  using BlockMap = absl::flat_hash_map<uint64_t, std::unique_ptr<EsdfBlock>>;

  /// `config` is the TSDF layer's geometry; `max_distance_m` the field's cap
  /// (EsdfConfig::max_distance_m). Throws std::invalid_argument when either is invalid.
  EsdfLayer(const LayerConfig& config, float max_distance_m);

  const LayerConfig& config() const { return config_; }
  float maxDistance() const { return max_distance_m_; }
  float voxelSize() const { return config_.voxel_size; }
  int voxelsPerSide() const { return config_.voxels_per_side; }
  int voxelsPerSideLog2() const { return voxels_per_side_log2_; }
  int voxelsPerBlock() const { return voxels_per_block_; }

  /// nullptr when the block is absent.
  EsdfBlock* getBlock(const BlockIndex& index);
  const EsdfBlock* getBlock(const BlockIndex& index) const;
  /// The existing block or a new one with every voxel unknown, at maxDistance() and without
  /// a site; `newly_allocated` (optional) tells which. Throws std::out_of_range outside the
  /// packable range.
  EsdfBlock* allocateBlock(const BlockIndex& index, bool* newly_allocated = nullptr);
  bool removeBlock(const BlockIndex& index);
  void clear() { blocks_.clear(); }
  size_t numBlocks() const { return blocks_.size(); }
  const BlockMap& blocks() const { return blocks_; }

  /// The voxel with this global index, nullptr when its block is absent.
  const EsdfVoxel* getVoxel(const GlobalVoxelIndex& index) const;
  EsdfVoxel* getVoxel(const GlobalVoxelIndex& index);
  /// Global voxel index whose cell contains `point` (layer frame, metres).
  GlobalVoxelIndex globalVoxelIndexFromPoint(const Eigen::Vector3f& point) const {
    return gridIndexFromPoint(point, voxel_size_inv_);
  }
  /// Centre of a global voxel, metres.
  Eigen::Vector3f globalVoxelCenter(const GlobalVoxelIndex& index) const {
    return (index.cast<float>() + Eigen::Vector3f::Constant(0.5f)) * config_.voxel_size;
  }
  /// Linear index of a local voxel index inside a block (x fastest, as Block).
  int linearIndex(const GridIndex& local) const {
    return local.x() +
           ((local.y() + (local.z() << voxels_per_side_log2_)) << voxels_per_side_log2_);
  }

  /// A read-only copy for readers beside the writer of this layer: its blocks share this
  /// layer's voxels (copied only when this layer writes them next, EsdfBlock::mutableVoxels),
  /// with their own neighbour links. O(blocks): no voxel is copied here.
  std::shared_ptr<const EsdfLayer> snapshot();

  /// Bytes held: blocks plus the hash map's slot array; a snapshot counts its blocks'
  /// records and table but not the voxels it shares (its source counts those). O(1).
  size_t memoryBytes() const;
  /// Bytes one block holds.
  size_t bytesPerBlock() const {
    return sizeof(EsdfBlock) + static_cast<size_t>(voxels_per_block_) * sizeof(EsdfVoxel);
  }

 private:
  // Points `block`'s neighbour slots at the existing blocks and theirs at `target` (the block
  // itself when it arrives, null when it leaves).
  void link(EsdfBlock* block, EsdfBlock* target);

  LayerConfig config_;
  float max_distance_m_ = 0.0f;
  int voxels_per_side_log2_ = 0;
  int voxels_per_block_ = 0;
  float voxel_size_inv_ = 0.0f;
  bool is_snapshot_ = false;
  BlockMap blocks_;
};

}  // namespace cblox
