#include "daemon/tracker/tracker_lcm_node.h"

#include <cmath>
#include <optional>
#include <type_traits>
#include <utility>

#include <cblox/covariance_reply_t.hpp>
#include <cblox/frame_pose_t.hpp>
#include <cblox/heartbeat_t.hpp>
#include <cblox/keyframe_pose_batch_t.hpp>
#include <cblox/keyframe_t.hpp>

#include "daemon/common/heartbeat.h"
#include "daemon/common/lcm_messages.h"
#include "daemon/common/run_loop.h"

namespace cblox {
namespace {

int8_t toStateConstant(FramePoseState state) {
  switch (state) {
    case FramePoseState::kNotInitialized:
      return frame_pose_t::NOT_INITIALIZED;
    case FramePoseState::kOk:
      return frame_pose_t::OK;
    case FramePoseState::kLost:
      return frame_pose_t::LOST;
    case FramePoseState::kRelocalized:
      return frame_pose_t::RELOCALIZED;
    case FramePoseState::kLoopCorrected:
      return frame_pose_t::LOOP_CORRECTED;
    case FramePoseState::kMapReset:
      return frame_pose_t::MAP_RESET;
  }
  return frame_pose_t::LOST;
}

int8_t toReasonConstant(PoseUpdateReason reason) {
  switch (reason) {
    case PoseUpdateReason::kLocalBundleAdjustment:
      return keyframe_pose_batch_t::LOCAL_BA;
    case PoseUpdateReason::kLoopCorrection:
      return keyframe_pose_batch_t::LOOP_CORRECTION;
    case PoseUpdateReason::kGlobalBundleAdjustment:
      return keyframe_pose_batch_t::GLOBAL_BA;
  }
  return keyframe_pose_batch_t::LOCAL_BA;
}

}  // namespace

TrackerNode::Outputs TrackerLcmNode::outputs() {
  TrackerNode::Outputs out;
  out.frame_pose = [this](const FramePoseReport& r) {
    const frame_pose_t msg =
        toFramePoseMsg(r.utime, r.frame_id, r.T_G_C, toStateConstant(r.state), r.jump,
                       r.map_epoch, r.reference_keyframe_id);
    std::lock_guard<std::mutex> lock(publish_mutex_);
    lcm_->publish(config_.frame_pose_channel, &msg);
  };
  out.keyframe = [this](const KeyframeInfo& k) {
    const keyframe_t msg =
        toKeyframeMsg(k.timestamp_ns / 1000, k.id, static_cast<int64_t>(k.frame_id), k.T_G_K,
                      k.landmark_ids, node_->mapEpoch());
    std::lock_guard<std::mutex> lock(publish_mutex_);
    lcm_->publish(config_.keyframe_channel, &msg);
  };
  out.keyframe_poses = [this](const KeyframePoseBatch& batch, PoseUpdateReason reason) {
    const keyframe_pose_batch_t msg =
        toKeyframePoseBatchMsg(wallUtime(), toReasonConstant(reason), batch, node_->mapEpoch());
    std::lock_guard<std::mutex> lock(publish_mutex_);
    lcm_->publish(config_.keyframe_poses_channel, &msg);
  };
  out.covariance_reply = [this](const KeyframeCovarianceReply& reply) {
    covariance_reply_t msg;
    msg.utime = wallUtime();
    msg.map_epoch = node_->mapEpoch();
    msg.request_id = reply.request_id;
    for (const ConditionalCovariance& r : reply.results) {
      covariance_pair_t pair{};
      pair.keyframe_i = static_cast<int64_t>(r.i);
      pair.keyframe_j = static_cast<int64_t>(r.j);
      pair.ok = r.ok;
      pair.error = r.error;
      for (int row = 0; row < 6; ++row) {
        for (int col = 0; col < 6; ++col) pair.sigma_i_given_j[6 * row + col] = r.sigma(row, col);
      }
      pair.q = r.q;
      msg.pairs.push_back(std::move(pair));
    }
    msg.num_pairs = static_cast<int32_t>(msg.pairs.size());
    std::lock_guard<std::mutex> lock(publish_mutex_);
    lcm_->publish(config_.covariance_reply_channel, &msg);
  };
  return out;
}

void TrackerLcmNode::subscribe(TrackerNode* node) {
  node_ = node;
  guard_.setPeerWatch(&peers_, config_.heartbeat_channel);
  const auto refusedAs = [this](TrackerProblem problem) {
    return [this, problem](const std::string& description) {
      node_->reportProblem(problem, description);
    };
  };
  if (config_.tracker.mode == TrackerMode::kStereo) {
    guard_.subscribe<stereo_pair_t>(
        config_.stereo_channel,
        [this](const stereo_pair_t& m, const std::string& c) { onFrame(m, c); },
        refusedAs(TrackerProblem::kUndecodable));
  } else {
    guard_.subscribe<depth_frame_t>(
        config_.depth_channel,
        [this](const depth_frame_t& m, const std::string& c) { onFrame(m, c); },
        refusedAs(TrackerProblem::kUndecodable));
  }
  if (config_.tracker.initial_pose == InitialPose::kGroundTruth) {
    guard_.subscribe<pose_stamped_t>(
        config_.ground_truth_channel,
        [this](const pose_stamped_t& m, const std::string& c) { onGroundTruth(m, c); },
        refusedAs(TrackerProblem::kBadGroundTruth));
  }
  guard_.subscribe<covariance_request_t>(
      config_.covariance_request_channel,
      [this](const covariance_request_t& m, const std::string& c) { onCovarianceRequest(m, c); },
      refusedAs(TrackerProblem::kBadCovarianceRequest));
}

void TrackerLcmNode::publishHeartbeat(const TrackerStatus& s, const std::string& state) {
  HeartbeatBuilder hb("cblox-tracker", state);
  hb.add("frames_received", s.frames_received);
  hb.add("frames_processed", s.frames_processed);
  hb.add("source_restarts", s.source_restarts);
  hb.add("map_epoch", static_cast<uint64_t>(s.map_epoch));
  hb.add("frames_tracked", s.frames_tracked);
  hb.add("frames_lost", s.frames_lost);
  hb.add("frames_not_initialized", s.frames_not_initialized);
  hb.add("frames_dropped", s.frames_dropped);
  hb.add("frames_rejected", s.frames_rejected);
  hb.add("relocalizations", s.relocalizations);
  hb.add("resumed_keyframes", s.resumed_keyframes);
  hb.add("checkpoints_written", s.checkpoints_written);
  hb.add("checkpoint_failures", s.checkpoint_failures);
  hb.add("checkpoint_generation", s.checkpoint_generation);
  hb.add("last_checkpoint_ms", static_cast<uint64_t>(std::lround(s.last_checkpoint_ms)));
  hb.add("id_lease_failures", s.id_lease_failures);
  hb.add("loop_corrected_frames", s.loop_corrected_frames);
  hb.add("keyframes", s.keyframes);
  hb.add("landmarks", s.landmarks);
  hb.add("pose_batches", s.pose_batches);
  hb.add("loops_closed", s.loops_closed);
  hb.add("loops_rejected_drift", s.loops_rejected_drift);
  hb.add("essential_graphs_failed", s.essential_graphs_failed);
  hb.add("local_bundle_adjustments", s.local_bundle_adjustments);
  hb.add("local_bundle_adjustments_interrupted", s.local_bundle_adjustments_interrupted);
  hb.add("local_mapping_cpu_ms", static_cast<uint64_t>(std::llround(s.local_mapping_cpu_ms)));
  hb.add("global_bundle_adjustments", s.global_bundle_adjustments);
  hb.add("global_bundle_adjustments_abandoned", s.global_bundle_adjustments_abandoned);
  hb.add("covariance_requests", s.covariance_requests);
  hb.add("covariance_pairs_ok", s.covariance_pairs_ok);
  hb.add("covariance_pairs_failed", s.covariance_pairs_failed);
  hb.add("covariance_linearizations", s.covariance_linearizations);
  hb.add("covariance_reused", s.covariance_reused);
  hb.addMicroseconds("covariance_build_us", s.covariance_build_ms);
  hb.addMicroseconds("covariance_solve_us", s.covariance_solve_ms);
  hb.addMicroseconds("tracking_median_us", s.tracking_ms_median);
  hb.addMicroseconds("tracking_p95_us", s.tracking_ms_p95);
  hb.addMicroseconds("frame_median_us", s.frame_ms_median);
  hb.addMicroseconds("frame_p95_us", s.frame_ms_p95);
  for (size_t i = 0; i < kNumTrackerProblems; ++i) {
    hb.add(trackerProblemCounter(static_cast<TrackerProblem>(i)), s.problems[i]);
  }
  guard_.addTo(&hb);
  const heartbeat_t msg = hb.build();
  std::lock_guard<std::mutex> lock(publish_mutex_);
  lcm_->publish(config_.heartbeat_channel, &msg);
}

template <typename Msg>
void TrackerLcmNode::onFrame(const Msg& msg, const std::string& channel) {
  TrackerFrame frame;
  TrackerProblem problem = TrackerProblem::kUndecodable;
  std::string error;
  bool decoded = false;
  if constexpr (std::is_same_v<Msg, stereo_pair_t>) {
    decoded = decodeStereoPair(msg, &frame, &problem, &error);
  } else {
    decoded = decodeRgbdFrame(msg, &frame, &problem, &error);
  }
  if (!decoded) {
    node_->reportProblem(problem, channel + " frame " + std::to_string(msg.frame_id) + " (" +
                                      std::to_string(msg.utime) + " us): " + error);
    return;
  }
  node_->onFrame(std::move(frame));
}

void TrackerLcmNode::onGroundTruth(const pose_stamped_t& msg, const std::string&) {
  std::string error;
  const std::optional<Transformationd> T = fromPoseMsg(msg.T_G_C, &error);
  if (!T) {
    node_->reportProblem(
        TrackerProblem::kBadGroundTruth,
        "ground-truth pose of frame " + std::to_string(msg.frame_id) + ": " + error);
    return;
  }
  node_->onGroundTruth(msg.frame_id, msg.utime, *T);
}

void TrackerLcmNode::onCovarianceRequest(const covariance_request_t& msg, const std::string&) {
  KeyframeCovarianceRequest request;
  request.request_id = msg.request_id;
  for (size_t k = 0; k < msg.keyframe_i.size() && k < msg.keyframe_j.size(); ++k) {
    // A negative id is no keyframe: its bit pattern as uint64 names none either, so the
    // pair is answered "not in the BA linearization".
    request.pairs.push_back(KeyframePair{static_cast<uint64_t>(msg.keyframe_i[k]),
                                         static_cast<uint64_t>(msg.keyframe_j[k])});
  }
  node_->onCovarianceRequest(std::move(request), msg.map_epoch);
}

}  // namespace cblox
