// cblox-mapper: the dense mapper process. Integrates depth frames into a collection of TSDF
// subvolumes, moves subvolumes when keyframe poses are corrected, and exports meshes on
// command.
//
//   cblox-mapper --config config/mapper.yaml                       # ground-truth poses
//   cblox-mapper --pose-source tracker --output-dir /data/maps
//
// Subscribes: CBLOX_DEPTH (depth_frame_t); ground_truth mode: CBLOX_GT_POSE
// (pose_stamped_t); tracker mode: CBLOX_FRAME_POSE (frame_pose_t), CBLOX_KEYFRAME
// (keyframe_t), CBLOX_COV_REPLY (covariance_reply_t); both: CBLOX_KEYFRAME_POSES
// (keyframe_pose_batch_t), CBLOX_CMD (command_t).
// Publishes: CBLOX_MAP_STATUS (map_status_t) and CBLOX_HEARTBEAT (heartbeat_t) every second,
// CBLOX_CMD_REPLY (command_reply_t); tracker mode: CBLOX_COV_REQUEST (covariance_request_t)
// for the map maintenance's fusion candidates.
// Poses on CBLOX_GT_POSE / CBLOX_FRAME_POSE are of the body (primary camera) frame B; a depth
// frame's camera is placed at T_G_B * calibration.T_B_C.
// Exit status: 0 stopped by SIGINT/SIGTERM, 1 runtime error, 2 usage or configuration error.

#include <unistd.h>

#include <atomic>
#include <chrono>
#include <cmath>
#include <csignal>
#include <cstdio>
#include <iostream>
#include <mutex>
#include <optional>
#include <string>
#include <vector>

#include <cblox/command_reply_t.hpp>
#include <cblox/command_t.hpp>
#include <cblox/covariance_reply_t.hpp>
#include <cblox/covariance_request_t.hpp>
#include <cblox/depth_frame_t.hpp>
#include <cblox/frame_pose_t.hpp>
#include <cblox/heartbeat_t.hpp>
#include <cblox/keyframe_pose_batch_t.hpp>
#include <cblox/keyframe_t.hpp>
#include <cblox/map_status_t.hpp>
#include <cblox/pose_stamped_t.hpp>
#include <lcm/lcm-cpp.hpp>

#include "daemon/config/command_line.h"
#include "daemon/config/mapper_config.h"
#include "daemon/config/process_main.h"
#include "daemon/config/yaml_config.h"
#include "daemon/lcm/messages.h"
#include "daemon/mapper/mapper.h"

namespace cblox {
namespace {

using Clock = std::chrono::steady_clock;

void printUsage() {
  std::cout << "usage: cblox-mapper [--config FILE] [--pose-source ground_truth|tracker]\n"
               "                    [--output-dir DIR] [--lcm-url URL] [--quiet]\n"
               "  Runs until SIGINT/SIGTERM. Commands arrive on CBLOX_CMD (see cblox-ctl).\n"
               "  exit status: 0 stopped by signal, 1 runtime error, 2 usage/configuration\n";
}

struct Args {
  std::optional<std::string> config_file, pose_source, output_dir, lcm_url;
  bool quiet = false;
};

Args parseArgs(int argc, char** argv) {
  Args args;
  parseFlags(
      argc, argv, printUsage, {"--quiet"}, [&](const std::string&) { args.quiet = true; },
      [&](const std::string& flag, const std::string& value) {
        if (flag == "--config") {
          args.config_file = value;
        } else if (flag == "--pose-source") {
          args.pose_source = value;
        } else if (flag == "--output-dir") {
          args.output_dir = value;
        } else if (flag == "--lcm-url") {
          args.lcm_url = value;
        } else {
          return false;
        }
        return true;
      });
  return args;
}

MapperProcessConfig buildConfig(const Args& args) {
  MapperProcessConfig config =
      args.config_file ? loadMapperConfig(loadYamlFile(*args.config_file)) : MapperProcessConfig{};
  if (args.pose_source) config.mapper.pose_source = parsePoseSource(*args.pose_source);
  if (args.output_dir) config.mapper.output_dir = *args.output_dir;
  if (args.lcm_url) config.lcm_url = *args.lcm_url;
  if (const std::string e = config.validate(); !e.empty()) throw ConfigError(e);
  return config;
}

/// LCM <-> Mapper adapter: the handlers run on the LCM (main) thread; replies may be
/// published from the worker thread, so every publish goes through one mutex.
class MapperNode {
 public:
  MapperNode(const MapperProcessConfig& config, lcm::LCM* lcm, Mapper* mapper)
      : config_(config), lcm_(lcm), mapper_(mapper) {}

  void subscribe() {
    lcm_->subscribe(config_.depth_channel, &MapperNode::onDepth, this);
    if (config_.mapper.pose_source == PoseSource::kGroundTruth) {
      lcm_->subscribe(config_.ground_truth_channel, &MapperNode::onGroundTruth, this);
    } else {
      lcm_->subscribe(config_.frame_pose_channel, &MapperNode::onFramePose, this);
      lcm_->subscribe(config_.keyframe_channel, &MapperNode::onKeyframe, this);
      lcm_->subscribe(config_.covariance_reply_channel, &MapperNode::onCovarianceReply, this);
      mapper_->setCovarianceRequester(
          [this](const FusionCovarianceRequest& request) { publishCovarianceRequest(request); });
    }
    lcm_->subscribe(config_.keyframe_poses_channel, &MapperNode::onKeyframePoses, this);
    lcm_->subscribe(config_.command_channel, &MapperNode::onCommand, this);
  }

  void publishStatus(const MapperStatus& s) {
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
    std::lock_guard<std::mutex> lock(publish_mutex_);
    lcm_->publish(config_.map_status_channel, &msg);
  }

  void publishHeartbeat(const MapperStatus& s, const char* state) {
    heartbeat_t hb;
    hb.utime = wallUtime();
    hb.process = "cblox-mapper";
    hb.pid = static_cast<int32_t>(::getpid());
    hb.state = state;
    auto add = [&](const std::string& name, uint64_t value) {
      hb.counter_names.push_back(name);
      hb.counter_values.push_back(static_cast<int64_t>(value));
    };
    add("frames_received", s.frames_received);
    add("frames_integrated", s.frames_integrated);
    add("frames_dropped", s.frames_dropped);
    add("frames_rejected", s.frames_rejected);
    add("subvolumes", s.num_submaps);
    add("keyframes", s.keyframes_applied);
    add("pose_batches", s.keyframe_batches);
    add("exports_done", s.exports_done);
    add("exports_failed", s.exports_failed);
    for (size_t i = 0; i < kNumInputProblems; ++i) {
      add(std::string("rejected_") + inputProblemName(static_cast<InputProblem>(i)), s.problems[i]);
    }
    hb.num_counters = static_cast<int32_t>(hb.counter_names.size());
    std::lock_guard<std::mutex> lock(publish_mutex_);
    lcm_->publish(config_.heartbeat_channel, &hb);
  }

 private:
  template <typename Msg>
  bool decode(const lcm::ReceiveBuffer* rbuf, Msg* msg) {
    return msg->decode(rbuf->data, 0, static_cast<int>(rbuf->data_size)) >= 0;
  }

  void onDepth(const lcm::ReceiveBuffer* rbuf, const std::string& channel) {
    depth_frame_t msg;
    if (!decode(rbuf, &msg)) {
      mapper_->reportProblem(InputProblem::kDepthUndecodable,
                             channel + ": message does not decode");
      return;
    }
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

  void onGroundTruth(const lcm::ReceiveBuffer* rbuf, const std::string& channel) {
    pose_stamped_t msg;
    std::string error;
    if (!decode(rbuf, &msg)) {
      mapper_->reportProblem(InputProblem::kPoseUndecodable, channel + ": message does not decode");
      return;
    }
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

  void onFramePose(const lcm::ReceiveBuffer* rbuf, const std::string& channel) {
    frame_pose_t msg;
    if (!decode(rbuf, &msg)) {
      mapper_->reportProblem(InputProblem::kPoseUndecodable, channel + ": message does not decode");
      return;
    }
    TimedPose pose;
    pose.utime = msg.utime;
    pose.epoch = msg.map_epoch;
    pose.jump = msg.tracking_jump;
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

  void onKeyframe(const lcm::ReceiveBuffer* rbuf, const std::string& channel) {
    keyframe_t msg;
    if (!decode(rbuf, &msg)) {
      mapper_->reportProblem(InputProblem::kKeyframeInvalid, channel + ": message does not decode");
      return;
    }
    std::string error;
    const std::optional<Transformationd> T = fromPoseMsg(msg.T_G_K, &error);
    if (!T) {
      mapper_->reportProblem(InputProblem::kKeyframeInvalid,
                             "keyframe " + std::to_string(msg.keyframe_id) + ": " + error);
      return;
    }
    std::vector<uint64_t> landmarks;
    landmarks.reserve(msg.landmark_ids.size());
    for (const int64_t id : msg.landmark_ids) {
      if (id >= 0) landmarks.push_back(static_cast<uint64_t>(id));
    }
    mapper_->onKeyframe(msg.keyframe_id, msg.utime, *T, std::move(landmarks));
  }

  void publishCovarianceRequest(const FusionCovarianceRequest& request) {
    covariance_request_t msg;
    msg.utime = wallUtime();
    msg.request_id = request.request_id;
    for (const FusionPair& pair : request.pairs) {
      msg.keyframe_i.push_back(pair.newer_keyframe);  // Sigma_{newer | older}
      msg.keyframe_j.push_back(pair.older_keyframe);
    }
    msg.num_pairs = static_cast<int32_t>(msg.keyframe_i.size());
    std::lock_guard<std::mutex> lock(publish_mutex_);
    lcm_->publish(config_.covariance_request_channel, &msg);
  }

  void onCovarianceReply(const lcm::ReceiveBuffer* rbuf, const std::string& channel) {
    covariance_reply_t msg;
    if (!decode(rbuf, &msg)) {
      mapper_->reportProblem(InputProblem::kCovarianceReplyInvalid,
                             channel + ": message does not decode");
      return;
    }
    std::vector<FusionCovarianceAnswer> answers;
    answers.reserve(msg.pairs.size());
    for (const covariance_pair_t& pair : msg.pairs) {
      FusionCovarianceAnswer answer;
      answer.ok = pair.ok && std::isfinite(pair.q) && pair.q >= 0.0;
      answer.error = pair.ok && !answer.ok ? "q is not a finite, non-negative number" : pair.error;
      answer.q = answer.ok ? pair.q : 0.0;
      answers.push_back(std::move(answer));
    }
    mapper_->onCovarianceReply(msg.request_id, std::move(answers));
  }

  void onKeyframePoses(const lcm::ReceiveBuffer* rbuf, const std::string& channel) {
    keyframe_pose_batch_t msg;
    if (!decode(rbuf, &msg)) {
      mapper_->reportProblem(InputProblem::kKeyframePoseInvalid,
                             channel + ": message does not decode");
      return;
    }
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
      batch.emplace_back(msg.keyframe_ids[i], *T);
    }
    if (!batch.empty()) mapper_->onKeyframePoses(std::move(batch));
  }

  void onCommand(const lcm::ReceiveBuffer* rbuf, const std::string& channel) {
    command_t msg;
    if (!decode(rbuf, &msg)) {
      mapper_->reportProblem(InputProblem::kCommandInvalid, channel + ": message does not decode");
      return;
    }
    MapperCommand command;
    command.id = msg.command_id;
    command.name = msg.name;
    for (size_t i = 0; i < msg.arg_keys.size() && i < msg.arg_values.size(); ++i) {
      command.args[msg.arg_keys[i]] = msg.arg_values[i];
    }
    mapper_->onCommand(command, [this](const MapperReply& reply) { publishReply(reply); });
  }

  void publishReply(const MapperReply& reply) {
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

  const MapperProcessConfig& config_;
  lcm::LCM* lcm_;
  Mapper* mapper_;
  std::mutex publish_mutex_;
};

int run(const Args& args) {
  const MapperProcessConfig config = buildConfig(args);
  const MapperConfig& m = config.mapper;

  lcm::LCM lcm(config.lcm_url);
  if (!lcm.good()) {
    std::fprintf(stderr, "cblox-mapper: cannot open LCM (url '%s')\n", config.lcm_url.c_str());
    return 1;
  }
  Mapper mapper(m);
  std::string error;
  if (!mapper.start(&error)) {
    std::fprintf(stderr, "cblox-mapper: %s\n", error.c_str());
    return 1;
  }
  installStopHandlers();
  if (!args.quiet) {
    std::printf(
        "mapper: %s poses, %s integrator, voxel %.3f m, truncation %.3f m, %d thread(s); "
        "new subvolume every %d keyframes%s; output %s\n",
        poseSourceName(m.pose_source), integratorTypeName(m.integrator_type), m.layer.voxel_size,
        m.integrator.truncation_distance_m, m.integrator.num_threads,
        m.creation.max_keyframes_per_subvolume,
        m.pose_source == PoseSource::kGroundTruth
            ? (" (a keyframe every " + std::to_string(m.keyframe_every_n_frames) + " frames)")
                  .c_str()
            : "",
        mapper.outputDir().c_str());
    std::fflush(stdout);
  }

  MapperNode node(config, &lcm, &mapper);
  node.subscribe();

  const Clock::time_point start = Clock::now();
  uint64_t last_integrated = 0;
  Clock::time_point last_progress = start;
  auto progress = [&](const MapperStatus& s, const char* prefix) {
    const double dt = std::chrono::duration<double>(Clock::now() - last_progress).count();
    const double rate =
        dt > 0 ? static_cast<double>(s.frames_integrated - last_integrated) / dt : 0;
    last_integrated = s.frames_integrated;
    last_progress = Clock::now();
    std::printf(
        "mapper: %s%llu frames integrated (%.1f/s), %llu dropped, %llu rejected, "
        "%zu subvolumes (%llu fused), %zu blocks, %.1f MiB, integration median %.1f ms p99 "
        "%.1f ms\n",
        prefix, static_cast<unsigned long long>(s.frames_integrated), rate,
        static_cast<unsigned long long>(s.frames_dropped),
        static_cast<unsigned long long>(s.frames_rejected), s.num_submaps,
        static_cast<unsigned long long>(s.fusion.fused), s.num_blocks,
        static_cast<double>(s.memory_bytes) / 1048576.0, s.integration_ms_median,
        s.integration_ms_p99);
    std::fflush(stdout);
  };

  std::vector<PeriodicTask> tasks{{config.status_period_s, 0.0, [&] {
                                     const MapperStatus s = mapper.status();
                                     node.publishStatus(s);
                                     node.publishHeartbeat(s, "running");
                                   }}};
  if (!args.quiet) {
    tasks.push_back({config.progress_period_s, config.progress_period_s,
                     [&] { progress(mapper.status(), ""); }});
  }
  const int exit_code = serveUntilStopped(lcm, "cblox-mapper", tasks);
  mapper.stop();  // finishes the frame in hand and the export in hand
  const MapperStatus s = mapper.status();
  node.publishStatus(s);
  node.publishHeartbeat(s, "stopped");
  if (!args.quiet) progress(s, "stopped: ");
  return exit_code;
}

}  // namespace
}  // namespace cblox

int main(int argc, char** argv) {
  return cblox::runProcess("cblox-mapper",
                           [&] { return cblox::run(cblox::parseArgs(argc, argv)); });
}
