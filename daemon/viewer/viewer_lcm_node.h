#pragma once

// cblox-viewer's LCM side: subscribes the mesh stream, poses, keyframes, map status,
// heartbeats and local grids behind the message guard and feeds the ViewerModel; asks the
// mapper for a mesh refresh while the mesh is incomplete, and for exports the page asks for.

#include <atomic>
#include <chrono>
#include <cstdint>
#include <mutex>
#include <string>

#include <cblox/command_reply_t.hpp>
#include <cblox/frame_pose_t.hpp>
#include <cblox/heartbeat_t.hpp>
#include <cblox/keyframe_pose_batch_t.hpp>
#include <cblox/keyframe_t.hpp>
#include <cblox/local_grid_t.hpp>
#include <cblox/map_status_t.hpp>
#include <cblox/mesh_update_t.hpp>
#include <cblox/pose_stamped_t.hpp>
#include <cblox/subvolume_list_t.hpp>
#include <lcm/lcm-cpp.hpp>

#include "core/common/rate_limited_log.h"
#include "daemon/common/heartbeat.h"
#include "daemon/common/message_guard.h"
#include "daemon/viewer/viewer_config.h"
#include "daemon/viewer/viewer_model.h"

namespace cblox {

/// Counters of the viewer's LCM side. Plain value type.
struct ViewerLcmCounters {
  uint64_t mesh_updates = 0;      ///< applied
  uint64_t mesh_refused = 0;      ///< decoded but refused (counts, indices, meshes)
  uint64_t mesh_gaps = 0;         ///< updates after lost messages
  uint64_t refresh_requests = 0;  ///< mesh_refresh commands sent
  uint64_t exports_requested = 0;
  uint64_t bad_messages = 0;      ///< other messages whose content was refused (poses, grids)
};

/// LCM <-> ViewerModel. Handlers run on the LCM thread; requestExport() from any thread.
class ViewerLcmNode {
 public:
  /// `config`, `lcm` and `model` must outlive the node.
  ViewerLcmNode(const ViewerConfig& config, lcm::LCM* lcm, ViewerModel* model);

  void subscribe();
  /// Asks the mapper for a refresh when the mesh is not synced and refresh_retry_s passed
  /// since the last ask (the first call asks at once). Call periodically on the LCM thread.
  void tick();
  /// Sends export_mesh to the mapper; the reply goes to the model (setExportResult).
  void requestExport();
  ViewerLcmCounters counters() const;
  MessageGuard& messageGuard() { return guard_; }
  void addTo(HeartbeatBuilder* heartbeat) const;

 private:
  void onMeshUpdate(const mesh_update_t& msg);
  void onSubvolumes(const subvolume_list_t& msg);
  void onFramePose(const frame_pose_t& msg);
  void onGroundTruth(const pose_stamped_t& msg);
  void onKeyframe(const keyframe_t& msg);
  void onKeyframePoses(const keyframe_pose_batch_t& msg);
  void onMapStatus(const map_status_t& msg);
  void onHeartbeat(const heartbeat_t& msg);
  void onLocalGrid(const local_grid_t& msg);
  void onCommandReply(const command_reply_t& msg);
  void publishCommand(int64_t id, const std::string& name, const std::string& path);
  // Counts a message whose content was refused (kind: mesh update or other) and logs why, at
  // most once per 10 s per kind with the count of those not logged.
  void refuse(bool mesh, const std::string& why);

  const ViewerConfig& config_;
  lcm::LCM* lcm_;
  ViewerModel* model_;
  MessageGuard guard_;
  RateLimitedLog refusal_log_;
  std::mutex publish_mutex_;
  std::chrono::steady_clock::time_point last_refresh_request_{};
  bool asked_once_ = false;
  std::atomic<int64_t> pending_export_{-1};
  std::atomic<uint64_t> mesh_updates_{0}, mesh_refused_{0}, mesh_gaps_{0}, refresh_requests_{0},
      exports_requested_{0}, bad_messages_{0};
  const int64_t id_base_;  // command ids: this base plus a count (distinct from other senders)
  std::atomic<int64_t> next_command_{1};
};

}  // namespace cblox
