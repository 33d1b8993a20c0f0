#pragma once

// What cblox-viewer knows of the map and the pipeline (the mesh stream's mirror, subvolume
// poses, trajectory, keyframes, events, health, the distance slice) and what each connected
// browser still has to be sent. Browsers get the newest state, never a backlog: a change
// marks what it touched in every browser's outbox, and a browser's next message is built
// from the current state of what is marked (so a slow browser costs no memory beyond one
// mark per block, and no browser slows another or the LCM thread).
//
// Mesh messages to browsers (binary WebSocket frames, little-endian):
//   u32 type = 1, u32 flags (bit 0: drop every block held first), f32 block_size,
//   u32 num_removed, u32 num_blocks, f64 removed subvolume ids[num_removed], then per block:
//   f64 subvolume id, i32 index[3], u32 num_vertices (0: drop the block), u32 num_triangles,
//   u32 has_color, i16 position[3 * num_vertices] (mesh_update_t's quantisation), zero
//   padding to 4 bytes, u8 color[3 * num_vertices] if has_color, padding, u16
//   triangle[3 * num_triangles], padding.

#include <chrono>
#include <condition_variable>
#include <functional>
#include <cstddef>
#include <cstdint>
#include <deque>
#include <map>
#include <mutex>
#include <optional>
#include <set>
#include <string>
#include <utility>
#include <vector>

#include <Eigen/Core>

#include "core/geometry/se3.h"
#include "core/mapping/mesh_mirror.h"

namespace cblox {

/// One message for a browser: binary (mesh blocks, ws_mesh_format below) or JSON text.
struct BrowserMessage {
  bool binary = false;
  std::string data;
};

/// A process as its last heartbeat described it.
struct ProcessHealth {
  std::string name;
  int32_t pid = 0;
  std::string state;
  int64_t utime = 0;  ///< of the heartbeat, us since the Unix epoch
  std::vector<std::pair<std::string, int64_t>> counters;
};

/// A slice of the distance field near the vehicle, across the up axis (from
/// CBLOX_LOCAL_GRID): cells along G's axes `axis_u` and `axis_v` (the two other than the up
/// axis, ascending), at `level` along the up axis.
struct DistanceSlice {
  int axis_u = 0, axis_v = 1;
  Eigen::Vector2d origin = Eigen::Vector2d::Zero();  ///< minimum corner along (u, v), G
  double level = 0.0;  ///< coordinate of the cell centres along the up axis, G
  double resolution = 0.0;
  int nu = 0, nv = 0;
  /// Per cell, u fastest: millimetres (meaningless where the state is unknown).
  std::vector<int32_t> distance_mm;
  /// 0 unknown, 1 free, 2 occupied (local_grid_t's states).
  std::vector<int8_t> state;
  float max_distance_m = 0.0f;
};

/// The viewer's state and the browsers' outboxes. Thread-safety: every member function is
/// thread-safe (one mutex); waitForWork() blocks until a browser has something to send.
class ViewerModel {
 public:
  struct Settings {
    size_t max_trajectory_points = 20000;
    std::string up_axis = "z";
    bool allow_export = false;
  };
  explicit ViewerModel(Settings settings);

  // ---- Inputs (the LCM thread).
  MeshMirror::Result applyMeshUpdate(const MeshUpdate& update);
  void applySubvolumes(const SubvolumeList& list, int64_t utime);
  /// A vehicle pose (frame pose or ground truth). `from_tracker`: once the tracker's poses
  /// arrive, ground-truth poses are ignored (the tracker's estimate is what the map is in).
  /// `epoch`: the tracker's map epoch (a new one starts a new trajectory).
  void addVehiclePose(int64_t utime, const Transformationd& T_G_C, bool from_tracker,
                      int32_t epoch);
  void addKeyframe(int64_t key, const Transformationd& T_G_K);
  /// Corrected keyframe poses; `loop_closure` records an event with how far they moved.
  void moveKeyframes(const std::vector<std::pair<int64_t, Transformationd>>& poses,
                     bool loop_closure, int64_t utime);
  /// The mapper's fusion counter (map_status_t.subvolumes_fused): an increase is an event.
  void setFusedCount(int64_t fused, int64_t utime);
  void setHeartbeat(ProcessHealth health);
  void setSlice(DistanceSlice slice);
  /// An event on the timeline (also used by the viewer for refresh requests and exports).
  void addEvent(int64_t utime, const std::string& kind, const std::string& text);
  /// The result of an export the viewer asked for: a browser may download `file` as
  /// /export/<id>.ply when ok.
  void setExportResult(int64_t id, bool ok, const std::string& message, const std::string& file);
  /// The file of export `id`, empty when unknown or failed.
  std::string exportFile(int64_t id) const;

  // ---- Browsers.
  /// Registers a browser; everything is in its outbox. Returns its id.
  int addClient();
  void removeClient(int client);
  /// The next message for `client` (the state first, then mesh blocks of at most
  /// `max_mesh_bytes` mesh bytes, then the rest), false when nothing is pending.
  bool nextMessage(int client, size_t max_mesh_bytes, BrowserMessage* out);
  /// Waits until `client` has something to send (true) or `timeout` passes (false).
  bool waitForWork(int client, std::chrono::milliseconds timeout);
  /// Wakes every waiter (shutting down).
  void wakeAll();

  // ---- Status.
  bool meshSynced() const;
  bool meshComplete() const;
  size_t numBlocks() const;
  size_t numClients() const;

 private:
  struct Outbox {
    bool full_mesh = true;
    std::set<std::pair<SubmapId, uint64_t>> dirty_blocks;
    std::set<SubmapId> removed;
    bool state = true, vehicle = true, keyframes = true, health = true, slice = false, export_result = false;
    uint64_t trajectory_generation = 0;
    size_t trajectory_sent = 0;
    size_t events_sent = 0;
  };
  struct Event {
    int64_t utime;
    std::string kind, text;
  };
  void markAll(const std::function<void(Outbox&)>& mark);
  void addEventLocked(int64_t utime, const std::string& kind, const std::string& text);
  bool hasWork(const Outbox& o) const;
  std::string stateJson() const;
  std::string meshMessage(Outbox* o, size_t max_mesh_bytes);

  const Settings settings_;
  mutable std::mutex mutex_;
  std::condition_variable work_;
  MeshMirror mirror_;
  SubvolumeList previous_list_;
  std::map<int, Outbox> clients_;
  int next_client_ = 1;

  // Trajectory: thinned by half when full (generation bumps, browsers get it again).
  std::vector<Eigen::Vector3f> trajectory_;
  uint64_t trajectory_generation_ = 1;
  int64_t last_pose_utime_ = 0;
  int32_t tracker_epoch_ = -1;
  bool tracker_poses_ = false;
  std::optional<Transformationd> vehicle_;
  std::map<int64_t, Eigen::Vector3d> keyframes_;
  std::deque<Event> events_;
  size_t events_dropped_ = 0;  // oldest events dropped from the front
  static constexpr size_t kMaxEvents = 500;
  int64_t fused_ = -1;
  std::map<std::string, ProcessHealth> health_;
  std::optional<DistanceSlice> slice_;
  struct ExportResult {
    bool ok = false;
    std::string message, file;
  };
  std::map<int64_t, ExportResult> exports_;
  int64_t last_export_ = -1;
};

}  // namespace cblox
