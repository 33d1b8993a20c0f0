#pragma once

#include <cstdint>

namespace cblox {

/// What a voxel of the map says about its space. Unknown is an answer of its own: a voxel
/// that was never observed (TSDF weight below EsdfConfig::min_weight) is neither free nor
/// an obstacle, whatever distance it holds.
enum class VoxelState : uint8_t {
  kUnknown = 0,
  kFree = 1,
  kOccupied = 2,
};

/// "unknown", "free" or "occupied". Thread-safe.
const char* voxelStateName(VoxelState state);

/// One voxel of a distance field, 12 bytes. The distance a voxel answers is its own_distance
/// (esdf_query.h reads no other voxel).
///   own_distance: sites (kSite: every occupied voxel and the free voxels whose value is
///     below one voxel, see EsdfIntegrator): their value (the TSDF distance, on the free side
///     divided by the TSDF gradient's norm when above 1)
///     as of its last decrease by more than 1/8 voxel, increase by more than half a voxel, or
///     change across zero (the value the voxels that took the site were computed with; at
///     most 1/8 voxel above the current one or at most half a voxel below, same sign).
///     Other voxels with a site: the distance through it when the wave last assigned it
///     (what it answers). Voxels without a site: the layer's max distance.
///   site: offset in voxels from this voxel to the surface voxel nearest to it as far as the
///     wavefront knows; meaningful only with kHasSite. Surface voxels are their own site
///     (offset 0).
/// Not thread-safe: the owning EsdfLayer's user synchronises.
struct EsdfVoxel {
  static constexpr uint8_t kHasSite = 1;  ///< site points at a surface voxel
  static constexpr uint8_t kRaise = 2;    ///< on the raise wave (its site vanished)
  static constexpr uint8_t kSite = 4;     ///< this voxel is a surface voxel (a site)
  /// A site whose distance grew since the voxels that took it were computed: they are
  /// raised and refilled (they may now have a nearer site).
  static constexpr uint8_t kSiteMoved = 8;

  float own_distance = 0.0f;
  int16_t site[3] = {0, 0, 0};
  VoxelState state = VoxelState::kUnknown;
  uint8_t flags = 0;

  bool hasSite() const { return (flags & kHasSite) != 0; }
  bool isSite() const { return (flags & kSite) != 0; }
};
static_assert(sizeof(EsdfVoxel) == 12, "EsdfVoxel must stay 12 bytes");

}  // namespace cblox
