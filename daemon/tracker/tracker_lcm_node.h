#pragma once

// cblox-tracker's LCM side: subscribes the frame, ground-truth and covariance-request
// channels behind the message guard, hands them to the TrackerNode, and publishes its
// outputs (frame poses, keyframes, pose batches, covariance replies) and the heartbeat.

#include <unistd.h>

#include <mutex>
#include <string>

#include <cblox/covariance_request_t.hpp>
#include <cblox/depth_frame_t.hpp>
#include <cblox/pose_stamped_t.hpp>
#include <cblox/stereo_pair_t.hpp>
#include <lcm/lcm-cpp.hpp>

#include "daemon/common/message_guard.h"
#include "daemon/tracker/tracker_config.h"
#include "daemon/tracker/tracker_node.h"

namespace cblox {

/// LCM <-> TrackerNode adapter. The handlers run on the LCM (main) thread; results are
/// published from the tracking, local mapping, loop closing and covariance threads, so every
/// publish goes through one mutex. A message that does not decode is reported to the
/// TrackerNode as the problem of its channel; a handler that throws is caught by the guard.
/// Thread-safety: the outputs and publishHeartbeat() are thread-safe; subscribe() once, before
/// the LCM thread handles messages.
class TrackerLcmNode {
 public:
  /// `config` and `lcm` must outlive the node.
  TrackerLcmNode(const TrackerProcessConfig& config, lcm::LCM* lcm)
      : config_(config), lcm_(lcm), guard_(lcm) {}

  /// The TrackerNode's outputs, publishing on the configured channels.
  TrackerNode::Outputs outputs();
  /// Subscribes the input channels of the configured mode; `node` must outlive this object.
  void subscribe(TrackerNode* node);
  void publishHeartbeat(const TrackerStatus& s, const std::string& state);
  /// The message guard's counts (refused messages by kind, handler errors).
  MessageGuardCounts messageCounts() const { return guard_.counts(); }
  /// The guard every subscription goes through (e.g. to set its InputWatch before handling).
  MessageGuard& messageGuard() { return guard_; }

 private:
  // A CBLOX_STEREO (stereo_pair_t) or CBLOX_DEPTH (depth_frame_t) message.
  template <typename Msg>
  void onFrame(const Msg& msg, const std::string& channel);
  void onGroundTruth(const pose_stamped_t& msg, const std::string& channel);
  void onCovarianceRequest(const covariance_request_t& msg, const std::string& channel);

  const TrackerProcessConfig& config_;
  lcm::LCM* lcm_;
  TrackerNode* node_ = nullptr;
  MessageGuard guard_;
  PeerWatch peers_{"cblox-tracker", static_cast<int32_t>(::getpid())};  // a second cblox-tracker
  std::mutex publish_mutex_;
};

}  // namespace cblox
