#pragma once

// The map for a planner: one distance field per subvolume (core/esdf), each in its
// subvolume's own frame M, answered in the global frame G through the subvolumes' current
// poses. A loop closure that moves subvolumes moves their fields with them: no field is
// recomputed for a pose change.

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cstddef>
#include <cstdint>
#include <limits>
#include <map>
#include <memory>
#include <mutex>
#include <span>
#include <string>
#include <vector>

#include <Eigen/Core>
#include <Eigen/Geometry>

#include "core/common/timing_window.h"
#include "core/esdf/esdf_config.h"
#include "core/esdf/esdf_integrator.h"
#include "core/esdf/esdf_layer.h"
#include "core/esdf/esdf_voxel.h"
#include "core/geometry/se3.h"
#include "core/submap/submap.h"
#include "core/submap/submap_collection.h"

namespace cblox {

/// The planning map's answer at one point of G.
///   state: occupied when some subvolume's field says occupied there; else free when some
///     subvolume observed the point free; else unknown (no subvolume observed it).
///   distance: metres to the nearest obstacle surface that the subvolumes observing the point
///     know: the smallest of their answers (negative inside an obstacle), capped at
///     max_distance_m. A free answer is also at most the bound of every subvolume whose
///     field covers the point without having observed it (DistanceSample::bound: the
///     distance to an obstacle that subvolume observed nearby). A free answer is then
///     lowered beside the obstacle by EsdfConfig::surface_margin_voxels of the answering
///     field's voxels (lowerBesideSurface(): by the whole margin up to 1 + margin voxels,
///     by less over the next voxel, never below 0). NaN when unknown.
///   gradient: of the answering subvolume's field, rotated into G (about unit length,
///     pointing away from the obstacle; 1 + margin times that where the margin tapers off);
///     only with has_gradient.
///   submap: the subvolume whose field gave the distance (or the bound); -1 when unknown.
struct DistanceAnswer {
  VoxelState state = VoxelState::kUnknown;
  double distance = std::numeric_limits<double>::quiet_NaN();
  Eigen::Vector3d gradient = Eigen::Vector3d::Constant(std::numeric_limits<double>::quiet_NaN());
  bool has_gradient = false;
  int64_t submap = -1;
};

/// A dense copy of the planning map over an axis-aligned box of G (PlanningMap::localGrid),
/// for planners that keep their own. Cell (i, j, k) has its centre at
/// origin + (i + 0.5, j + 0.5, k + 0.5) * resolution; cells are stored x fastest, then y, z.
struct LocalGrid {
  Eigen::Vector3d origin = Eigen::Vector3d::Zero();  ///< minimum corner, G
  double resolution = 0.0;                           ///< cell edge, metres
  Eigen::Vector3i size = Eigen::Vector3i::Zero();    ///< cells per axis
  std::vector<VoxelState> state;                     ///< per cell
  std::vector<float> distance;                       ///< per cell; NaN where unknown

  size_t index(int i, int j, int k) const {
    return static_cast<size_t>(i) +
           static_cast<size_t>(size.x()) *
               (static_cast<size_t>(j) + static_cast<size_t>(size.y()) * static_cast<size_t>(k));
  }
  Eigen::Vector3d cellCenter(int i, int j, int k) const {
    return origin + (Eigen::Vector3d(i, j, k) + Eigen::Vector3d::Constant(0.5)) * resolution;
  }
};

/// Counters and sizes of the planning map. Plain value type.
struct PlanningMapStats {
  size_t fields = 0;        ///< subvolumes with a distance field
  size_t blocks = 0;        ///< distance-field blocks over all fields
  size_t band_blocks = 0;   ///< of them, band blocks (EsdfConfig::band_blocks)
  size_t memory_bytes = 0;  ///< bytes the fields hold
  uint64_t updates = 0;     ///< field updates (incremental or rebuilt)
  uint64_t rebuilds = 0;    ///< of those, whole-field rebuilds
};

/// The distance fields of a SubmapCollection's subvolumes, and the queries over them.
///
/// Who calls what (the mapper's threads; any single-threaded user may call everything):
/// - refresh(): one thread at a time, the owner of finished layers (the mapper's
///   fusion/export worker: finished subvolumes every refresh_period_s and after a fusion,
///   all of them after a load and on Mapper::syncPlanningMap).
/// - refreshActive(): the active subvolume, from a thread at the integrator's priority.
/// - setPoses(): after a pose batch (the mapper's maintenance thread).
/// - query(), queryBatch(), localGrid(), stats(), memoryBytes(): any thread, any time.
/// Queries never wait for a field's computation: each field is computed in a working layer
/// of its own and then published as an immutable snapshot (EsdfLayer::snapshot(), blocks
/// shared copy-on-write), and a query samples the snapshots it took from the index, without
/// any lock; it sees every field whole, as of its last publication. Two threads that
/// refresh the same field take turns (its update mutex); a periodic refresh of finished
/// subvolumes skips a field the other thread is computing. refresh(kAll) and
/// refreshActive() hold an active subvolume's layer lock (blocking integration) only while
/// they read the blocks that changed, not while the waves run.
/// Lock order: field update mutex -> subvolume layer lock -> field bytes mutex -> index mutex.
class PlanningMap {
 public:
  /// Throws std::invalid_argument with EsdfConfig::validate()'s message when invalid.
  explicit PlanningMap(const EsdfConfig& config);
  PlanningMap(const PlanningMap&) = delete;
  PlanningMap& operator=(const PlanningMap&) = delete;

  const EsdfConfig& config() const { return config_; }

  /// Which subvolumes refresh() computes.
  enum class Scope {
    kFinished,  ///< finished ones only, never touching a layer integration is writing;
                ///< a field another thread is computing is left for the next refresh
    kAll,       ///< the active one too, reading its changed blocks under Submap::lockLayer();
                ///< waits for a field another thread is computing
  };
  /// Makes the fields follow `collection`: fields of subvolumes no longer in it are dropped;
  /// a subvolume in `scope` without a field, or whose Submap::revision() moved since its
  /// field was computed, has its field updated from the TSDF blocks that changed
  /// (EsdfIntegrator), a finished one reading its layer without a lock (call on the thread
  /// that owns finished layers); every field takes its subvolume's current pose. Its
  /// duration goes into refreshMs().
  void refresh(const SubmapCollection& collection, Scope scope);
  /// The active subvolume's field only, as refresh(kAll) computes it: its changed blocks are
  /// read under Submap::lockLayer() (integration waits meanwhile), the waves run after the
  /// lock is released. For a thread of its own at the integrator's priority (the mapper's
  /// "cblox-esdf"), so that the planner sees the space being mapped now, not once the
  /// subvolume is finished; never at idle priority, where holding the layer lock would
  /// stall integration. Safe beside refresh() on another thread (each has its own
  /// integrator; a field's update mutex orders their updates).
  void refreshActive(const SubmapCollection& collection);
  /// The subvolumes' current poses (ids without a field are ignored).
  void setPoses(const std::vector<SubmapPose>& poses);

  /// The answer at `p_G` (see DistanceAnswer): every field whose blocks' bounding box holds
  /// the point is sampled with trilinear interpolation (esdf_query.h).
  DistanceAnswer query(const Eigen::Vector3d& p_G) const;
  /// query() for each point, into `answers` (resized), with one snapshot of the poses and
  /// fields for the whole batch. With num_threads > 1 the points are split into contiguous
  /// parts of at least kMinPointsPerThread, answered on the calling thread and helpers it
  /// starts; the answers are the same whatever the split.
  void queryBatch(std::span<const Eigen::Vector3d> points_G, std::vector<DistanceAnswer>* answers,
                  int num_threads = 1) const;
  /// The fewest points queryBatch gives one thread.
  static constexpr size_t kMinPointsPerThread = 512;
  /// The names a planner looks for: the same answer as query() (distance and gradient are
  /// always computed together), and whether some subvolume observed the point.
  DistanceAnswer distanceAndGradient(const Eigen::Vector3d& p_G) const { return query(p_G); }
  bool isObserved(const Eigen::Vector3d& p_G) const {
    return query(p_G).state != VoxelState::kUnknown;
  }

  /// At most this many cells in one localGrid().
  static constexpr size_t kMaxGridCells = size_t{1} << 22;
  /// Samples the box [min_G, max_G] at cell centres `resolution` apart (query() per cell,
  /// one pose snapshot for the whole grid) into *grid: ceil(side / resolution) cells per
  /// axis, a side within 1e-6 cells of a whole number counting as that number. Refused (false,
  /// *error says why, nothing allocated) when a bound is not finite, max_G is not above min_G on
  /// every axis, resolution is not finite and > 0, or the box has more than kMaxGridCells cells.
  bool localGrid(const Eigen::Vector3d& min_G, const Eigen::Vector3d& max_G, double resolution,
                 LocalGrid* grid, std::string* error) const;

  /// An axis-aligned box of G that holds every field's blocks at the subvolumes' current
  /// poses (each block's bounding sphere), or an empty box when no field has a block.
  /// O(blocks).
  Eigen::AlignedBox3d boundsG() const;

  PlanningMapStats stats() const;
  /// Durations of the refresh() calls that updated a field, ms.
  const TimingWindow& refreshMs() const { return refresh_ms_; }
  /// Bytes the fields hold, and their two integrators' working memory
  /// (EsdfIntegrator::workingBytes: the high-water mark of the waves' queues). O(1).
  size_t memoryBytes() const { return fieldBytes() + workingBytes(); }
  /// The two integrators' working memory alone. O(1).
  size_t workingBytes() const {
    return working_bytes_.load(std::memory_order_relaxed) +
           active_working_bytes_.load(std::memory_order_relaxed);
  }
  /// Bytes the fields will hold once they follow a collection of `tsdf_blocks` blocks of
  /// `layer`'s geometry (one field block per TSDF block, and band blocks in the proportion
  /// the computed fields have them), or what they hold when more, plus the integrators'
  /// working memory: what a memory cap counts, so that the fields' lag behind integration
  /// cannot overrun it. O(1).
  size_t projectedBytes(size_t tsdf_blocks, const LayerConfig& layer) const;

 private:
  struct Field {
    Field(const LayerConfig& geometry, float max_distance_m) : work(geometry, max_distance_m) {}
    std::mutex update_mutex;   // guards work and revision
    EsdfLayer work;            // the integrators' layer; queries read its snapshots
    uint64_t revision = 0;     // Submap::revision() when last computed
    std::mutex bytes_mutex;    // guards counted_* and dropped
    size_t counted_bytes = 0;  // this field's share of memory_bytes_
    size_t counted_blocks = 0;       // ... of field_blocks_
    size_t counted_band_blocks = 0;  // ... of band_blocks_
    bool dropped = false;      // its subvolume left the collection
  };
  /// One field as the queries see it: its latest snapshot, its pose and the bounding box of
  /// its blocks in M.
  struct IndexEntry {
    SubmapId id = 0;
    std::shared_ptr<Field> field;
    std::shared_ptr<const EsdfLayer> layer;  // null until first computed
    Transformationd T_M_G;
    Eigen::Matrix3d R_G_M = Eigen::Matrix3d::Identity();
    Eigen::AlignedBox3f box_M;  // empty until the field has a block
  };

  std::shared_ptr<Field> fieldFor(const Submap& submap);
  // Computes one field with `integrator` (the caller holds its update mutex): stages it
  // from `layer`, releases `layer_lock` (when it holds one), finishes it, publishes a
  // snapshot into the index.
  void updateField(const Submap& submap, const TsdfLayer& layer,
                   std::unique_lock<std::mutex>* layer_lock, EsdfIntegrator* integrator,
                   Field* field);
  // One subvolume's field, when its layer changed since: an active subvolume's read under
  // its layer lock; a finished one's only by the owner of finished layers (`owns_finished`;
  // otherwise left to it). Without `wait`, a field another thread is computing is skipped.
  // True when the field was updated.
  bool refreshOne(const Submap& submap, EsdfIntegrator* integrator, bool owns_finished, bool wait);
  // Adds the time since `start` to refreshMs().
  void recordRefresh(std::chrono::steady_clock::time_point start);
  std::vector<IndexEntry> indexSnapshot() const;
  // The answer at p_G over `index`; a free one lowered by config_.surface_margin_voxels of
  // the answering field's voxels (lowerBesideSurface).
  DistanceAnswer sample(const std::vector<IndexEntry>& index, const Eigen::Vector3d& p_G) const;

  const EsdfConfig config_;
  EsdfIntegrator integrator_;           // refresh()'s
  std::mutex active_integrator_mutex_;  // one refreshActive() at a time
  EsdfIntegrator active_integrator_;    // refreshActive()'s
  TimingWindow refresh_ms_{200};

  mutable std::mutex index_mutex_;
  std::map<SubmapId, IndexEntry> index_;

  std::atomic<size_t> memory_bytes_{0};
  std::atomic<size_t> field_blocks_{0};  // published blocks over all fields
  std::atomic<size_t> band_blocks_{0};   // of them, band blocks
  std::atomic<size_t> working_bytes_{0};         // integrator_.workingBytes()
  std::atomic<size_t> active_working_bytes_{0};  // active_integrator_.workingBytes()
  size_t fieldBytes() const { return memory_bytes_.load(std::memory_order_relaxed); }
  std::atomic<uint64_t> updates_{0}, rebuilds_{0};
};

}  // namespace cblox
