#pragma once

#include <cstddef>
#include <cstdint>
#include <vector>

#include "core/esdf/distance_bucket_queue.h"
#include "core/esdf/esdf_config.h"
#include "core/esdf/esdf_layer.h"
#include "core/tsdf/tsdf_layer.h"

namespace cblox {

/// What one EsdfIntegrator call did.
struct EsdfUpdateStats {
  size_t tsdf_blocks_read = 0;   ///< TSDF blocks whose voxels were read (new or changed)
  size_t esdf_blocks_added = 0;  ///< distance-field blocks allocated
  size_t sites_added = 0;        ///< voxels that became (or changed as) obstacles
  size_t sites_removed = 0;      ///< obstacle voxels that stopped being obstacles
  size_t voxels_popped = 0;      ///< wavefront steps
  size_t queue_peak_bytes = 0;   ///< the waves' queue storage at its fullest, bytes
  bool rebuilt = false;          ///< the whole field was recomputed
};

/// Computes a subvolume's Euclidean signed distance field (EsdfLayer) from its TSDF layer,
/// in the subvolume's own frame, and keeps it up to date incrementally.
///
/// The field covers every allocated TSDF block and, with EsdfConfig::band_blocks = b, the
/// blocks within b blocks of them (band blocks: every voxel unknown; they only carry sites).
/// Per voxel:
///   - state: unknown when the TSDF weight is 0 or below min_weight; occupied when observed
///     with TSDF distance <= 0; free otherwise.
///   - sites: every occupied voxel, and the free voxels whose value is below one voxel size,
///     so that every surface point has a site within half a voxel diagonal (also at convex
///     corners and edges, where the nearest occupied voxel centre can be a voxel away).
///     Occupied sites answer their TSDF distance (<= 0). A free voxel's value is its TSDF
///     distance divided by the norm of the TSDF's gradient there when it exceeds 1
///     (differences of the observed voxels of the same block; 1 without them), computed for
///     TSDF distances below 4 voxels: a projective TSDF measures along the view ray,
///     1/cos(angle to the surface normal) times the distance across the surface, and its
///     gradient grows by the same factor, so a voxel within one voxel of a surface seen at a
///     grazing angle, or beside a convex edge that rays pass, is a site although its TSDF
///     distance exceeds a voxel. Where the TSDF is exact the quotient is the TSDF value, or
///     below it by a fraction of a voxel on curved surfaces (never above it). Occupied
///     voxels are sites whatever their value: a projective TSDF seen at a grazing angle has
///     no voxel within one voxel of zero.
///   - every other voxel (free or unknown) carries a site s that minimises
///     |x - s| + max(tsdf(s), -voxel) as far as the wavefront knows, where |x - s| is the
///     distance between voxel centres and tsdf(s) the site's value (above); it answers that
///     value as the wave computed it (with s's value then; esdf_query.h reads it without
///     looking s up), at least 0, capped at max_distance_m. A site keeps the value its
///     voxels were computed with while its current value is at most a key step (1/8 voxel)
///     below it or at most half a voxel above it, on the same side of zero: its voxels then
///     answer at most 1/8 voxel more, or up to half a voxel less (the safe side), than a
///     rebuild. A site that shrinks by more spreads a lower wave; one that grows by more
///     raises the voxels that took it through its neighbours, and a voxel that took it past
///     neighbouring sites may keep the value it was computed with. Through a free-side site the
///     formula is an upper bound of the true distance (triangle inequality), through an
///     occupied one it may undershoot; the minimum over the sites near the surface is within
///     a fraction of a voxel of the truth on exact TSDFs (the analytic tests bound it).
///   The sites are carried by a 26-connected brushfire ordered by that distance (quantised to
///   1/8 voxel), after Lau, Sprunk and Burgard, "Efficient grid-based spatial representations
///   for robot navigation in dynamic environments" (RAS 2013): lower waves spread new sites,
///   raise waves clear voxels whose site stopped being one before the lower wave refills
///   them. Surfaces in space no TSDF block covers are not seen; a band block stays until the
///   next rebuild.
///
/// Incremental contract: update() reads only TSDF blocks that are new or whose
/// Block::changeCount() moved since the last call, so integrators must mark changed blocks
/// (setUpdated(true)). When a TSDF block the field was computed from is gone, update() falls
/// back to rebuild(). A caller that removes and re-creates blocks between calls calls
/// rebuild() itself.
///
/// Thread safety: one call at a time per integrator; the TSDF layer must not be written and
/// the EsdfLayer must not be read during a call.
class EsdfIntegrator {
 public:
  /// Throws std::invalid_argument with EsdfConfig::validate()'s message when invalid.
  explicit EsdfIntegrator(const EsdfConfig& config);

  const EsdfConfig& config() const { return config_; }

  /// Brings `esdf` up to date with `tsdf` (see the class comment). Throws
  /// std::invalid_argument when the two layers' geometries differ, when esdf's
  /// maxDistance() is not config().max_distance_m, or when max_distance_m spans more than
  /// 30000 voxels (sites are 16-bit offsets).
  EsdfUpdateStats update(const TsdfLayer& tsdf, EsdfLayer* esdf);
  /// Recomputes `esdf` from scratch.
  EsdfUpdateStats rebuild(const TsdfLayer& tsdf, EsdfLayer* esdf);

  /// update() in two steps, so that a caller can release the TSDF layer's lock in between:
  /// stage() reads the new and changed TSDF blocks (the layer must not be written during it)
  /// and queues the waves; finish() runs them without reading the TSDF. Between the two,
  /// `esdf` must not be read or changed, nor this integrator used otherwise. Same exceptions
  /// as update() (from stage()).
  EsdfUpdateStats stage(const TsdfLayer& tsdf, EsdfLayer* esdf);
  void finish(EsdfLayer* esdf, EsdfUpdateStats* stats);

  /// The waves' working memory as a memory cap counts it: the high-water mark of the queue's
  /// storage over all calls (a wave's peak; after a call at most 256 KiB of it stays
  /// allocated, but the allocator seldom returns the rest to the system) and the distance
  /// table. 0 before the first call; it never decreases, so a cap's stage does not move back
  /// and forth with each wave. O(1).
  size_t workingBytes() const;

 private:
  // A voxel in the queue: its block's EsdfBlock::queue_slot and its linear index.
  struct Entry {
    uint32_t slot;
    uint32_t linear;
  };
  void push(uint32_t key, const EsdfBlock* block, int linear) {
    queue_.push(key, {block->queue_slot, static_cast<uint32_t>(linear)});
  }
  struct VoxelRef {
    EsdfBlock* block = nullptr;
    GridIndex local = GridIndex::Zero();  ///< inside `block`
    int linear = 0;
    const EsdfVoxel& voxel() const { return block->voxel(linear); }
    /// For writing (EsdfBlock::mutableVoxels): re-fetch after any other write to `block`.
    EsdfVoxel& mutableVoxel() const { return block->mutableVoxels()[linear]; }
  };

  void prepare(const EsdfLayer& esdf);
  // Clears `esdf` and stages it whole.
  EsdfUpdateStats restage(const TsdfLayer& tsdf, EsdfLayer* esdf);
  /// The voxel at `local` + `delta` (local may leave the block by one), or an empty ref.
  /// Inline: the waves call it for every neighbour of a voxel on a block's border.
  VoxelRef neighbour(EsdfLayer* esdf, EsdfBlock* block, const GridIndex& local,
                     const GridIndex& delta) const {
    const GridIndex n = local + delta;
    const int log2 = voxels_per_side_log2_, mask = voxels_per_side_ - 1;
    VoxelRef ref;
    // Arithmetic shifts give the neighbour's block offset (-1, 0, 1) per axis.
    ref.block = block->neighbours[static_cast<size_t>(
        EsdfBlock::neighbourSlot(n.x() >> log2, n.y() >> log2, n.z() >> log2))];
    if (ref.block != nullptr) {
      ref.local = GridIndex(n.x() & mask, n.y() & mask, n.z() & mask);
      ref.linear = esdf->linearIndex(ref.local);
    }
    return ref;
  }
  /// The norm of the TSDF's gradient at voxel `linear` of `tsdf` (differences of observed
  /// voxels inside the block), in distance per distance, at least 1.
  float gradientNorm(const Block& tsdf, int linear) const;
  /// Reads one TSDF block into its distance-field block: states, sites added and removed.
  void readBlock(EsdfLayer* esdf, EsdfBlock* block, EsdfUpdateStats* stats);
  /// Pushes the sited voxels of `block`'s neighbours that touch it (it is new).
  void seedFromNeighbours(EsdfLayer* esdf, EsdfBlock* block);
  /// Whether the voxel `ref` (with a site, not a site itself) holds less than its site gives
  /// now: the site vanished, or its distance grew since the voxel took it.
  bool stale(const EsdfLayer& esdf, const VoxelRef& ref, const EsdfVoxel& voxel) const;
  /// The site at `local` + `offset` (from `block`), or null when that voxel is no site.
  const EsdfVoxel* siteAt(const EsdfLayer& esdf, const EsdfBlock& block, const GridIndex& local,
                          const Eigen::Vector3i& offset) const;
  /// A site's TSDF distance as the distance through it counts it: at least -one voxel (a
  /// surface voxel's centre lies within one voxel of the surface; a deeper occupied voxel is
  /// never nearer to a point outside than the surface voxels in front of it).
  float siteDistance(float tsdf_distance) const { return std::max(tsdf_distance, -voxel_size_); }
  /// The queue key of a distance: 1/8 voxel steps, clamped to the queue's range.
  uint32_t keyOf(float distance) const;

  EsdfConfig config_;
  float voxel_size_ = 0.0f;
  int voxels_per_side_ = 0;
  int voxels_per_side_log2_ = 0;
  float max_reach_ = 0.0f;  // farthest distance a wave carries a site, metres
  uint32_t max_key_ = 0;
  std::vector<GridIndex> neighbours_;   // the 26 offsets
  std::vector<int> neighbour_linear_;   // the same as linear index steps inside a block
  std::vector<float> centre_distance_;  // metres, by squared offset length in voxels
  float centre_distance_voxel_ = 0.0f;
  DistanceBucketQueue<Entry> queue_{0};
  std::vector<EsdfBlock*> slots_;  // the layer's blocks by queue_slot, numbered by stage()
  size_t queue_high_water_bytes_ = 0;
};

}  // namespace cblox
