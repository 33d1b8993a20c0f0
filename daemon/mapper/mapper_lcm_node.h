#pragma once

// cblox-mapper's LCM side: subscribes the mapper's input channels behind the message guard,
// turns messages into Mapper calls, and publishes status, heartbeat, covariance requests and
// command replies.

#include <unistd.h>

#include <atomic>
#include <cstddef>
#include <map>
#include <memory>
#include <vector>
#include <mutex>
#include <string>

#include <cblox/command_t.hpp>
#include <cblox/covariance_reply_t.hpp>
#include <cblox/depth_frame_t.hpp>
#include <cblox/frame_pose_t.hpp>
#include <cblox/keyframe_pose_batch_t.hpp>
#include <cblox/keyframe_t.hpp>
#include <cblox/pose_stamped_t.hpp>
#include <lcm/lcm-cpp.hpp>

#include "core/mapping/mapper.h"
#include "daemon/common/message_guard.h"
#include "daemon/mapper/mapper_process_config.h"
#include "daemon/mapper/mesh_stream_node.h"
#include "daemon/mapper/planning_node.h"

namespace cblox {

/// LCM <-> Mapper adapter. The handlers run on the LCM (main) thread; replies may be
/// published from the worker thread, so every publish goes through one mutex. Every message
/// passes the MessageGuard first: a message that does not decode is reported to the Mapper
/// as the input problem of its channel (counted and logged), and a handler that throws is
/// caught there. Thread-safety: publish*() are thread-safe; subscribe() once, before the LCM
/// thread handles messages.
class MapperNode {
 public:
  /// `config`, `lcm` and `mapper` must outlive the node.
  MapperNode(const MapperProcessConfig& config, lcm::LCM* lcm, Mapper* mapper)
      : config_(config), lcm_(lcm), mapper_(mapper), guard_(lcm) {}

  /// Gives the Mapper the mesh stream's sinks (mesh_stream_node.h). Call before
  /// Mapper::start().
  void attachMeshStream() { mesh_stream_.attach(mapper_); }
  /// Subscribes the channels of the configured pose source and sets the Mapper's covariance
  /// requester (tracker mode); starts the planner interface (planning_node.h) and subscribes
  /// its request channel.
  void subscribe();
  void publishStatus(const MapperStatus& s);
  void publishHeartbeat(const MapperStatus& s, const char* state);
  /// The message guard's counts (refused messages by kind, handler errors).
  MessageGuardCounts messageCounts() const { return guard_.counts(); }
  /// The guard every subscription goes through (e.g. to set its InputWatch before handling).
  MessageGuard& messageGuard() { return guard_; }

 private:
  void onDepth(const depth_frame_t& msg, const std::string& channel);
  void onGroundTruth(const pose_stamped_t& msg, const std::string& channel);
  void onFramePose(const frame_pose_t& msg, const std::string& channel);
  void onKeyframe(const keyframe_t& msg, const std::string& channel);
  void onCovarianceReply(const covariance_reply_t& msg, const std::string& channel);
  void onKeyframePoses(const keyframe_pose_batch_t& msg, const std::string& channel);
  void onCommand(const command_t& msg, const std::string& channel);
  void publishCovarianceRequest(const FusionCovarianceRequest& request);
  void publishReply(const MapperReply& reply);

  const MapperProcessConfig& config_;
  lcm::LCM* lcm_;
  Mapper* mapper_;
  MessageGuard guard_;
  PeerWatch peers_{"cblox-mapper", static_cast<int32_t>(::getpid())};  // a second cblox-mapper
  std::mutex publish_mutex_;  // also guards older_epoch_pairs_
  // The tracker's map epoch (of its newest frame pose or keyframe): covariance requests are
  // about it. Keyframe and landmark ids are keyed by epoch (map_epoch_key.h).
  std::atomic<int32_t> tracker_epoch_{0};
  // Per covariance request in flight: which pairs were of an earlier epoch (sent as -1).
  static constexpr size_t kMaxRequestsRemembered = 64;
  std::map<int64_t, std::vector<bool>> older_epoch_pairs_;
  std::unique_ptr<PlanningNode> planning_;  // from subscribe()
  MeshStreamNode mesh_stream_{config_, lcm_};
};

}  // namespace cblox
