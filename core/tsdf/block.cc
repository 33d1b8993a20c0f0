#include "core/tsdf/block.h"

#include <bit>

namespace cblox {

Block::Block(const BlockIndex& index, int voxels_per_side, float voxel_size)
    : index_(index),
      voxels_per_side_(voxels_per_side),
      voxels_per_side_log2_(std::countr_zero(static_cast<unsigned>(voxels_per_side))),
      num_voxels_(voxels_per_side * voxels_per_side * voxels_per_side),
      voxel_size_(voxel_size),
      origin_(index.cast<float>() * voxel_size * static_cast<float>(voxels_per_side)),
      voxels_(new TsdfVoxel[static_cast<size_t>(num_voxels_)]()) {}

int Block::countObservedVoxels() const {
  int count = 0;
  for (int i = 0; i < num_voxels_; ++i) count += voxels_[static_cast<size_t>(i)].observed() ? 1 : 0;
  return count;
}

}  // namespace cblox
