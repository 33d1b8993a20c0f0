#pragma once

// The mapper's incremental mesh stream: every period, the meshes of the blocks that changed
// since the last period, per subvolume in the subvolume's own frame, and the subvolume list
// with the poses that place them (so a loop closure moves meshes without resending them).

#include <atomic>
#include <chrono>
#include <cstddef>
#include <cstdint>
#include <functional>
#include <map>
#include <mutex>
#include <optional>
#include <string>
#include <vector>

#include <absl/container/flat_hash_map.h>

#include "core/common/priority_runner.h"
#include "core/common/timing_window.h"
#include "core/mapping/mesh_stream_config.h"
#include "core/mapping/mesh_update.h"
#include "core/mesh/block_mesher.h"
#include "core/mesh/mesh_integrator.h"
#include "core/submap/submap_collection.h"

namespace cblox {

/// Counters of a MeshStreamer since start. Plain value type.
struct MeshStreamStats {
  uint64_t periods = 0;         ///< tick() calls
  uint64_t messages = 0;        ///< MeshUpdates handed out
  uint64_t blocks_sent = 0;     ///< block meshes handed out (removals included)
  uint64_t bytes_sent = 0;      ///< their mesh bytes (MeshUpdate::payloadBytes)
  uint64_t refreshes = 0;       ///< full refreshes begun (asked, periodic, new map)
  uint64_t blocks_refused = 0;  ///< blocks whose mesh could not be quantised (not sent)
  size_t blocks_pending = 0;    ///< held back by the budget after the last period
  float period_ms_median = 0.0f;  ///< tick() wall time
  float period_ms_p99 = 0.0f;
};

/// Meshes and hands out the blocks that changed (MeshUpdate), and the subvolume list
/// (SubvolumeList), once per tick().
///
/// What a receiver that applies every MeshUpdate in order holds (mesh_mirror.h): for every
/// subvolume, the BlockMesher mesh of every block with a surface, quantised
/// (quantized_block_mesh.h), as of the period that sent it. A block's mesh depends on the
/// block and its 7 upper neighbours, so a block is re-meshed when it or one of them changed
/// (Block::changeCount moved), was allocated or removed. Blocks without a surface are sent
/// only to remove one the receiver holds. Subvolumes no longer in the collection are sent as
/// removed. A new map (the map epoch moved), requestRefresh() and every refresh_period_s
/// begin a full refresh: its first message has refresh_start, and every block with a surface
/// follows. A period sends at most max_bytes_per_period mesh bytes (the active subvolume's
/// blocks first, then the others by id); the rest waits (blocks_pending), meshed when sent.
///
/// Threads: tick() runs on the mapper's fusion/export worker, the owner of finished layers,
/// which it reads without a lock; the active subvolume's changed blocks (and the neighbours
/// their meshes read) are copied under Submap::lockLayer() by a PriorityRunner thread at the
/// integrator's niceness while the worker waits (the worker runs at idle priority and must
/// not hold the lock integration waits for), and meshed from the copy on the worker.
/// Thread-safety: tick() from one thread at a time (the worker); requestRefresh() and
/// stats() from any thread; start()/stop() from one thread.
class MeshStreamer {
 public:
  using UpdateSink = std::function<void(const MeshUpdate&)>;
  using SubvolumeSink = std::function<void(const SubvolumeList&)>;
  using LogSink = std::function<void(const std::string&)>;

  /// `collection` must outlive the streamer; `map_epoch` gives Mapper::mapEpoch(). Sinks are
  /// called on the tick()'s thread. Throws std::invalid_argument when `config` or `mesh` is
  /// invalid.
  MeshStreamer(const MeshStreamConfig& config, const MeshConfig& mesh,
               const SubmapCollection* collection, std::function<int64_t()> map_epoch,
               int copy_niceness, UpdateSink on_update, SubvolumeSink on_subvolumes,
               LogSink log);
  ~MeshStreamer();
  MeshStreamer(const MeshStreamer&) = delete;
  MeshStreamer& operator=(const MeshStreamer&) = delete;

  /// Starts the copy thread. Until then (and after stop()) tick() reads an active
  /// subvolume under its layer lock on the calling thread (single-threaded use, tests).
  void start();
  void stop();

  /// One period: see the class comment.
  void tick();
  /// The next tick() begins a full refresh. Thread-safe.
  void requestRefresh() { refresh_requested_.store(true, std::memory_order_release); }
  /// Thread-safe.
  MeshStreamStats stats() const;

 private:
  struct BlockRecord {
    uint64_t change_count = 0;
    bool in_layer = true;      // false: removed; kept until its removal is sent
    bool has_surface = false;  // the receivers hold a non-empty mesh of it
  };
  struct SubmapState {
    absl::flat_hash_map<uint64_t, BlockRecord> blocks;
    // Blocks to send, by key: a mesh made from the active subvolume's copy, or nullopt (made
    // from the finished layer when sent).
    std::map<uint64_t, std::optional<QuantizedBlockMesh>> pending;
    uint64_t revision = kNeverScanned;
    // Bounds of the blocks in the layer (block indices), recomputed when bounds_stale.
    bool bounds_stale = true, any_block = false;
    BlockIndex lo = BlockIndex::Zero(), hi = BlockIndex::Zero();
  };
  static constexpr uint64_t kNeverScanned = UINT64_MAX;

  // Updates `st`'s records from `layer` and returns the blocks whose mesh may have changed
  // (all of them with `everything`); removed blocks with a surface become pending removals.
  std::vector<uint64_t> scan(const TsdfLayer& layer, SubmapState* st, bool everything) const;
  void scanFinished(const Submap& submap, SubmapState* st, bool everything);
  void scanActive(const Submap& submap, SubmapState* st, bool everything);
  // Meshes `key` of `layer` and quantises it (false: refused, counted and logged).
  bool meshBlock(const TsdfLayer& layer, uint64_t key, QuantizedBlockMesh* out);
  void send(const std::vector<std::shared_ptr<Submap>>& submaps,
            std::vector<SubmapId> removed, bool refresh_start);
  SubvolumeList subvolumeList(const std::vector<std::shared_ptr<Submap>>& submaps);

  const MeshStreamConfig config_;
  const MeshConfig mesh_config_;
  const SubmapCollection* const collection_;
  const std::function<int64_t()> map_epoch_;
  const UpdateSink on_update_;
  const SubvolumeSink on_subvolumes_;
  const LogSink log_;
  const double block_size_;

  PriorityRunner copier_;
  bool copier_running_ = false;
  BlockMesher mesher_;  // the tick()'s thread only
  Mesh scratch_mesh_;   // the tick()'s thread only

  // The tick()'s thread only.
  std::map<SubmapId, SubmapState> state_;
  int64_t epoch_ = 0;
  bool first_tick_ = true;
  int64_t sequence_ = 0;
  std::chrono::steady_clock::time_point next_refresh_;

  std::atomic<bool> refresh_requested_{false};
  mutable std::mutex stats_mutex_;
  MeshStreamStats stats_;
  TimingWindow period_ms_{120};
};

}  // namespace cblox
