#include "daemon/mapper/mapper_lcm_node.h"

#include <cmath>
#include <optional>
#include <utility>
#include <vector>

#include <cblox/command_reply_t.hpp>
#include <cblox/covariance_request_t.hpp>
#include <cblox/heartbeat_t.hpp>
#include <cblox/map_status_t.hpp>

#include "core/mapping/map_epoch_key.h"
#include "daemon/common/heartbeat.h"
#include "daemon/common/lcm_messages.h"
#include "daemon/common/run_loop.h"

namespace cblox {

void MapperNode::subscribe() {
  guard_.setPeerWatch(&peers_, config_.heartbeat_channel);
  const auto refusedAs = [this](InputProblem problem) {
    return [this, problem](const std::string& description) {
      mapper_->reportProblem(problem, description);
    };
  };
  guard_.subscribe<depth_frame_t>(
      config_.depth_channel, [this](const depth_frame_t& m, const std::string& c) { onDepth(m, c); },
      refusedAs(InputProblem::kDepthUndecodable));
  if (config_.mapper.pose_source == PoseSource::kGroundTruth) {
    guard_.subscribe<pose_stamped_t>(
        config_.ground_truth_channel,
        [this](const pose_stamped_t& m, const std::string& c) { onGroundTruth(m, c); },
        refusedAs(InputProblem::kPoseUndecodable));
  } else {
    guard_.subscribe<frame_pose_t>(
        config_.frame_pose_channel,
        [this](const frame_pose_t& m, const std::string& c) { onFramePose(m, c); },
        refusedAs(InputProblem::kPoseUndecodable));
    guard_.subscribe<keyframe_t>(
        config_.keyframe_channel,
        [this](const keyframe_t& m, const std::string& c) { onKeyframe(m, c); },
        refusedAs(InputProblem::kKeyframeInvalid));
    guard_.subscribe<covariance_reply_t>(
        config_.covariance_reply_channel,
        [this](const covariance_reply_t& m, const std::string& c) { onCovarianceReply(m, c); },
        refusedAs(InputProblem::kCovarianceReplyInvalid));
    mapper_->setCovarianceRequester(
        [this](const FusionCovarianceRequest& request) { publishCovarianceRequest(request); });
  }
  guard_.subscribe<keyframe_pose_batch_t>(
      config_.keyframe_poses_channel,
      [this](const keyframe_pose_batch_t& m, const std::string& c) { onKeyframePoses(m, c); },
      refusedAs(InputProblem::kKeyframePoseInvalid));
  guard_.subscribe<command_t>(
      config_.command_channel, [this](const command_t& m, const std::string& c) { onCommand(m, c); },
      refusedAs(InputProblem::kCommandInvalid));
  planning_ = std::make_unique<PlanningNode>(config_, lcm_, mapper_);
  planning_->subscribe(&guard_);
}

void MapperNode::publishStatus(const MapperStatus& s) {
  map_status_t msg;
  msg.utime = wallUtime();
  msg.num_subvolumes = static_cast<int32_t>(s.num_submaps);
  msg.active_subvolume_id = s.active_submap_id;
  msg.num_blocks = static_cast<int64_t>(s.num_blocks);
  msg.memory_bytes = static_cast<int64_t>(s.memory_bytes);
  msg.frames_received = static_cast<int64_t>(s.frames_received);
  msg.frames_integrated = static_cast<int64_t>(s.frames_integrated);
  msg.frames_dropped = static_cast<int64_t>(s.frames_dropped);
  msg.frames_rejected = static_cast<int64_t>(s.frames_rejected);
  msg.integration_ms_last = s.integration_ms_last;
  msg.integration_ms_median = s.integration_ms_median;
  msg.integration_ms_p99 = s.integration_ms_p99;
  msg.fusion_candidates = static_cast<int64_t>(s.fusion.candidates);
  msg.covariance_requested = static_cast<int64_t>(s.fusion.requested);
  msg.subvolumes_fused = static_cast<int64_t>(s.fusion.fused);
  msg.rejected_by_q = static_cast<int64_t>(s.fusion.rejected_by_q);
  msg.checkpoint_generation = static_cast<int64_t>(s.checkpoint_generation);
  msg.checkpoints_written = static_cast<int64_t>(s.checkpoints_written);
  msg.checkpoint_failures = static_cast<int64_t>(s.checkpoint_failures);
  msg.last_checkpoint_utime = s.last_checkpoint_utime;
  msg.last_checkpoint_ms = s.last_checkpoint_ms;
  msg.checkpoint_dir = config_.mapper.checkpoint.dir;
  std::lock_guard<std::mutex> lock(publish_mutex_);
  lcm_->publish(config_.map_status_channel, &msg);
}

void MapperNode::publishHeartbeat(const MapperStatus& s, const char* state) {
  HeartbeatBuilder hb("cblox-mapper", state);
  hb.add("frames_received", s.frames_received)
      .add("frames_integrated", s.frames_integrated)
      .add("frames_dropped", s.frames_dropped)
      .add("frames_rejected", s.frames_rejected)
      .add("frames_pending", s.frames_pending)  // queue depth (cblox-ctl status --all)
      .add("subvolumes", static_cast<uint64_t>(s.num_submaps))
      .add("keyframes", s.keyframes_applied)
      .add("pose_batches", s.keyframe_batches)
      .add("exports_done", s.exports_done)
      .add("exports_failed", s.exports_failed)
      .add("checkpoints_written", s.checkpoints_written)
      .add("checkpoint_failures", s.checkpoint_failures)
      .add("checkpoint_generation", s.checkpoint_generation)
      .add("last_checkpoint_ms", static_cast<uint64_t>(std::lround(s.last_checkpoint_ms)))
      .add("source_restarts", s.source_restarts)
      .add("map_bytes", static_cast<uint64_t>(s.memory_bytes))
      .add("memory_cap_bytes", static_cast<uint64_t>(s.memory_cap_bytes))
      .add("memory_cap_stage", static_cast<uint64_t>(s.memory_cap.state))
      .add("frames_near_only", s.memory_cap.frames_near_only)
      .add("frames_at_memory_cap", s.memory_cap.frames_at_cap)
      .add("blocks_refused", s.memory_cap.blocks_refused);
  for (size_t i = 0; i < kNumInputProblems; ++i) {
    hb.add(std::string("rejected_") + inputProblemName(static_cast<InputProblem>(i)),
           s.problems[i]);
  }
  if (planning_) planning_->addTo(&hb);
  if (config_.mapper.mesh_stream.enabled) mesh_stream_.addTo(&hb, s.mesh_stream);
  guard_.addTo(&hb);
  const heartbeat_t msg = hb.build();
  std::lock_guard<std::mutex> lock(publish_mutex_);
  lcm_->publish(config_.heartbeat_channel, &msg);
}

void MapperNode::onDepth(const depth_frame_t& msg, const std::string& /*channel*/) {
  DepthFrame frame;
  frame.utime = msg.utime;
  frame.frame_id = msg.frame_id;
  std::string error;
  const std::string what = "depth frame " + std::to_string(msg.frame_id) + ": ";
  if (!fromDepthImageMsg(msg.depth, &frame.depth, &error)) {
    mapper_->reportProblem(InputProblem::kDepthUndecodable, what + error);
    return;
  }
  if (msg.has_color && !fromImageMsg(msg.color, &frame.color, &error)) {
    mapper_->reportProblem(InputProblem::kDepthUndecodable, what + "colour: " + error);
    return;
  }
  const std::optional<PinholeIntrinsics> intrinsics = fromCalibrationMsg(msg.calibration, &error);
  if (!intrinsics) {
    mapper_->reportProblem(InputProblem::kDepthUndecodable, what + "calibration: " + error);
    return;
  }
  const std::optional<Transformationd> T_B_D = fromPoseMsg(msg.calibration.T_B_C, &error);
  if (!T_B_D) {
    mapper_->reportProblem(InputProblem::kDepthUndecodable, what + "calibration.T_B_C: " + error);
    return;
  }
  frame.intrinsics = *intrinsics;
  frame.T_B_D = *T_B_D;
  frame.min_depth_m = msg.min_depth_m;
  frame.max_depth_m = msg.max_depth_m;
  mapper_->onDepthFrame(std::move(frame));
}

void MapperNode::onGroundTruth(const pose_stamped_t& msg, const std::string& /*channel*/) {
  std::string error;
  const std::optional<Transformationd> T = fromPoseMsg(msg.T_G_C, &error);
  if (!T) {
    mapper_->reportProblem(InputProblem::kPoseInvalid,
                           "ground-truth pose at " + std::to_string(msg.utime) + " us: " + error);
    return;
  }
  TimedPose pose;
  pose.utime = msg.utime;
  pose.T_G_C = *T;
  mapper_->onFramePose(pose);
}

void MapperNode::onFramePose(const frame_pose_t& msg, const std::string& /*channel*/) {
  if (msg.map_epoch < 0 || msg.map_epoch > kMaxMapEpoch) {
    mapper_->reportProblem(InputProblem::kPoseUndecodable,
                           "frame pose at " + std::to_string(msg.utime) + " us: map epoch " +
                               std::to_string(msg.map_epoch) + " out of range");
    return;
  }
  tracker_epoch_ = msg.map_epoch;
  TimedPose pose;
  pose.utime = msg.utime;
  pose.epoch = msg.map_epoch;
  pose.jump = msg.tracking_jump;
  // Another version's or program's value outside this epoch's ids: no reference (the frame
  // is integrated as without one).
  pose.reference_keyframe = epochKey(msg.map_epoch, msg.reference_keyframe_id).value_or(-1);
  switch (msg.tracking_state) {
    case frame_pose_t::OK:
      break;
    case frame_pose_t::NOT_INITIALIZED:
    case frame_pose_t::LOST:
      pose.tracking_ok = false;
      break;
    case frame_pose_t::RELOCALIZED:
    case frame_pose_t::LOOP_CORRECTED:
    case frame_pose_t::MAP_RESET:
      pose.jump = true;
      break;
    default:
      mapper_->reportProblem(InputProblem::kPoseUndecodable,
                             "frame pose at " + std::to_string(msg.utime) +
                                 " us: unknown tracking_state " +
                                 std::to_string(static_cast<int>(msg.tracking_state)));
      return;
  }
  std::string error;
  const std::optional<Transformationd> T = fromPoseMsg(msg.T_G_C, &error);
  if (T) {
    pose.T_G_C = *T;
  } else if (pose.tracking_ok) {
    mapper_->reportProblem(InputProblem::kPoseInvalid,
                           "frame pose at " + std::to_string(msg.utime) + " us: " + error);
    return;
  }  // a lost pose may carry anything: the mapper stores it as "not tracked"
  mapper_->onFramePose(pose);
}

void MapperNode::onKeyframe(const keyframe_t& msg, const std::string& /*channel*/) {
  std::string error;
  const std::optional<Transformationd> T = fromPoseMsg(msg.T_G_K, &error);
  if (!T) {
    mapper_->reportProblem(InputProblem::kKeyframeInvalid,
                           "keyframe " + std::to_string(msg.keyframe_id) + ": " + error);
    return;
  }
  const std::optional<int64_t> key = epochKey(msg.map_epoch, msg.keyframe_id);
  if (!key) {
    mapper_->reportProblem(InputProblem::kKeyframeInvalid,
                           "keyframe " + std::to_string(msg.keyframe_id) + " of map epoch " +
                               std::to_string(msg.map_epoch) + ": id or epoch out of range");
    return;
  }
  tracker_epoch_ = msg.map_epoch;
  std::vector<uint64_t> landmarks;  // keyed by epoch too: ids restart with every map
  landmarks.reserve(msg.landmark_ids.size());
  for (const int64_t id : msg.landmark_ids) {
    if (const std::optional<int64_t> landmark = epochKey(msg.map_epoch, id)) {
      landmarks.push_back(static_cast<uint64_t>(*landmark));
    }
  }
  mapper_->onKeyframe(*key, msg.utime, *T, std::move(landmarks));
}

void MapperNode::publishCovarianceRequest(const FusionCovarianceRequest& request) {
  // The tracker answers about its current map only: a pair of an earlier epoch goes out as
  // ids -1 (it fails there) and its answer says why (older_epoch_pairs_).
  covariance_request_t msg;
  msg.utime = wallUtime();
  msg.map_epoch = tracker_epoch_.load();
  msg.request_id = request.request_id;
  std::vector<bool> older_epoch;
  for (const FusionPair& pair : request.pairs) {
    const bool current = epochOfKey(pair.newer_keyframe) == msg.map_epoch &&
                         epochOfKey(pair.older_keyframe) == msg.map_epoch;
    older_epoch.push_back(!current);
    msg.keyframe_i.push_back(current ? idOfKey(pair.newer_keyframe) : -1);  // Sigma_{i | j}
    msg.keyframe_j.push_back(current ? idOfKey(pair.older_keyframe) : -1);  // i newer, j older
  }
  msg.num_pairs = static_cast<int32_t>(msg.keyframe_i.size());
  std::lock_guard<std::mutex> lock(publish_mutex_);
  older_epoch_pairs_[msg.request_id] = std::move(older_epoch);
  while (older_epoch_pairs_.size() > kMaxRequestsRemembered) {
    older_epoch_pairs_.erase(older_epoch_pairs_.begin());
  }
  lcm_->publish(config_.covariance_request_channel, &msg);
}

void MapperNode::onCovarianceReply(const covariance_reply_t& msg, const std::string& /*channel*/) {
  std::vector<bool> older_epoch;
  {
    std::lock_guard<std::mutex> lock(publish_mutex_);
    auto it = older_epoch_pairs_.find(msg.request_id);
    if (it != older_epoch_pairs_.end()) {
      older_epoch = std::move(it->second);
      older_epoch_pairs_.erase(it);
    }
  }
  std::vector<FusionCovarianceAnswer> answers;
  answers.reserve(msg.pairs.size());
  for (size_t k = 0; k < msg.pairs.size(); ++k) {
    const covariance_pair_t& pair = msg.pairs[k];
    FusionCovarianceAnswer answer;
    answer.ok = pair.ok && std::isfinite(pair.q) && pair.q >= 0.0;
    answer.error = pair.ok && !answer.ok ? "q is not a finite, non-negative number" : pair.error;
    if (k < older_epoch.size() && older_epoch[k]) {
      answer.ok = false;
      answer.error = "keyframes of an earlier map epoch: the tracker keeps only its current map";
    }
    answer.q = answer.ok ? pair.q : 0.0;
    answers.push_back(std::move(answer));
  }
  mapper_->onCovarianceReply(msg.request_id, std::move(answers));
}

void MapperNode::onKeyframePoses(const keyframe_pose_batch_t& msg, const std::string& /*channel*/) {
  std::vector<std::pair<KeyframeId, Transformationd>> batch;
  batch.reserve(msg.keyframe_ids.size());
  for (size_t i = 0; i < msg.keyframe_ids.size() && i < msg.poses.size(); ++i) {
    std::string error;
    const std::optional<Transformationd> T = fromPoseMsg(msg.poses[i], &error);
    if (!T) {
      mapper_->reportProblem(
          InputProblem::kKeyframePoseInvalid,
          "keyframe pose " + std::to_string(msg.keyframe_ids[i]) + ": " + error);
      continue;
    }
    const std::optional<int64_t> key = epochKey(msg.map_epoch, msg.keyframe_ids[i]);
    if (!key) {
      mapper_->reportProblem(InputProblem::kKeyframePoseInvalid,
                             "keyframe pose " + std::to_string(msg.keyframe_ids[i]) +
                                 " of map epoch " + std::to_string(msg.map_epoch) +
                                 ": id or epoch out of range");
      continue;
    }
    batch.emplace_back(*key, *T);
  }
  if (!batch.empty()) mapper_->onKeyframePoses(std::move(batch));
}

void MapperNode::onCommand(const command_t& msg, const std::string& /*channel*/) {
  MapperCommand command;
  command.id = msg.command_id;
  command.name = msg.name;
  for (size_t i = 0; i < msg.arg_keys.size() && i < msg.arg_values.size(); ++i) {
    command.args[msg.arg_keys[i]] = msg.arg_values[i];
  }
  mapper_->onCommand(command, [this](const MapperReply& reply) { publishReply(reply); });
}

void MapperNode::publishReply(const MapperReply& reply) {
  command_reply_t msg;
  msg.utime = wallUtime();
  msg.command_id = reply.id;
  msg.ok = reply.ok;
  msg.message = reply.message;
  for (const auto& [key, value] : reply.values) {
    msg.value_keys.push_back(key);
    msg.values.push_back(value);
  }
  msg.num_values = static_cast<int32_t>(msg.value_keys.size());
  std::lock_guard<std::mutex> lock(publish_mutex_);
  lcm_->publish(config_.command_reply_channel, &msg);
}

}  // namespace cblox
