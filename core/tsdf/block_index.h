#pragma once

#include <cmath>
#include <cstdint>

#include <Eigen/Core>

namespace cblox {

/// Integer index of a block (or of a voxel, in global voxel units) on a regular grid.
using GridIndex = Eigen::Vector3i;
using BlockIndex = GridIndex;
using GlobalVoxelIndex = GridIndex;

/// Each axis of a grid index is packed into 21 bits (two's complement offset), so the
/// usable range per axis is [-2^20, 2^20 - 1]: +-10 km of 1 cm voxels.
inline constexpr int kGridIndexBits = 21;
inline constexpr int32_t kGridIndexMin = -(1 << (kGridIndexBits - 1));
inline constexpr int32_t kGridIndexMax = (1 << (kGridIndexBits - 1)) - 1;

/// True when every component fits the packed range.
inline bool gridIndexInRange(const GridIndex& index) {
  return index.minCoeff() >= kGridIndexMin && index.maxCoeff() <= kGridIndexMax;
}

/// Packs a grid index into one 63-bit key (bijective on the valid range). Thread-safe.
inline uint64_t packGridIndex(const GridIndex& index) {
  constexpr uint64_t kMask = (uint64_t{1} << kGridIndexBits) - 1;
  const auto x = static_cast<uint64_t>(static_cast<int64_t>(index.x()) - kGridIndexMin) & kMask;
  const auto y = static_cast<uint64_t>(static_cast<int64_t>(index.y()) - kGridIndexMin) & kMask;
  const auto z = static_cast<uint64_t>(static_cast<int64_t>(index.z()) - kGridIndexMin) & kMask;
  return x | (y << kGridIndexBits) | (z << (2 * kGridIndexBits));
}

/// Inverse of packGridIndex. Thread-safe.
inline GridIndex unpackGridIndex(uint64_t key) {
  constexpr uint64_t kMask = (uint64_t{1} << kGridIndexBits) - 1;
  return GridIndex(
      static_cast<int32_t>(static_cast<int64_t>(key & kMask) + kGridIndexMin),
      static_cast<int32_t>(static_cast<int64_t>((key >> kGridIndexBits) & kMask) + kGridIndexMin),
      static_cast<int32_t>(static_cast<int64_t>((key >> (2 * kGridIndexBits)) & kMask) +
                           kGridIndexMin));
}

/// Grid index of the cell of side `cell_size_inv`^-1 that contains `point`
/// (cells are [i, i+1) * cell_size). Thread-safe.
inline GridIndex gridIndexFromPoint(const Eigen::Vector3f& point, float cell_size_inv) {
  return GridIndex(static_cast<int>(std::floor(point.x() * cell_size_inv)),
                   static_cast<int>(std::floor(point.y() * cell_size_inv)),
                   static_cast<int>(std::floor(point.z() * cell_size_inv)));
}

/// floor(x) for finite |x| < 2^31, without a libm call (baseline x86-64 has no SSE4.1
/// roundss). Callers guarantee the range; NaN or larger values are undefined behaviour.
inline int fastFloor(float x) {
  const int truncated = static_cast<int>(x);
  return truncated - (x < static_cast<float>(truncated) ? 1 : 0);
}

/// gridIndexFromPoint for hot loops whose points are known finite and inside the packable
/// grid (|point * cell_size_inv| < 2^31). Thread-safe.
inline GridIndex gridIndexFromPointUnchecked(const Eigen::Vector3f& point, float cell_size_inv) {
  return GridIndex(fastFloor(point.x() * cell_size_inv), fastFloor(point.y() * cell_size_inv),
                   fastFloor(point.z() * cell_size_inv));
}

/// Splits a global voxel index into its block index and the voxel's index inside the block.
/// `voxels_per_side` = 1 << `voxels_per_side_log2`. Arithmetic shift gives floor division
/// for negative indices. Thread-safe.
inline void splitGlobalVoxelIndex(const GlobalVoxelIndex& global, int voxels_per_side_log2,
                                  BlockIndex* block, GridIndex* local) {
  const int mask = (1 << voxels_per_side_log2) - 1;
  *block = BlockIndex(global.x() >> voxels_per_side_log2, global.y() >> voxels_per_side_log2,
                      global.z() >> voxels_per_side_log2);
  *local = GridIndex(global.x() & mask, global.y() & mask, global.z() & mask);
}

/// A 64-bit finaliser (splitmix64) that spreads packed keys over all bits. Thread-safe.
inline uint64_t mixHash(uint64_t key) {
  key ^= key >> 30;
  key *= 0xbf58476d1ce4e5b9ULL;
  key ^= key >> 27;
  key *= 0x94d049bb133111ebULL;
  key ^= key >> 31;
  return key;
}

}  // namespace cblox
