// cblox-tracker: the sparse stereo / RGB-D SLAM process. Tracks every frame, builds the
// sparse map (keyframes, landmarks, local BA, loop closure, global BA) and publishes the
// poses the dense mapper hangs its subvolumes on.
//
//   cblox-tracker --config config/tracker.yaml          # stereo, calibration from the messages
//   cblox-tracker --initial-pose-from-gt                 # simulator: G = the simulator's frame
//   cblox-tracker --calibration config/calibration/sim_rig.yaml     # camera from a file
//   cblox-tracker --mode rgbd                            # depth + registered colour
//
// Subscribes: stereo mode CBLOX_STEREO (stereo_pair_t), RGB-D mode CBLOX_DEPTH
// (depth_frame_t with registered colour); initial_pose ground_truth: CBLOX_GT_POSE
// (pose_stamped_t); CBLOX_COV_REQUEST (covariance_request_t) from the mapper.
// Publishes: CBLOX_FRAME_POSE (frame_pose_t) for every frame processed, CBLOX_KEYFRAME
// (keyframe_t) for every new keyframe, CBLOX_KEYFRAME_POSES (keyframe_pose_batch_t) after
// every local BA, loop correction and global BA, CBLOX_HEARTBEAT (heartbeat_t) every second,
// CBLOX_COV_REPLY (covariance_reply_t) for every request (computed on the covariance
// service's own low-priority thread).
// Frame poses are of the tracked camera (the rectified left camera, or the RGB-D camera).
// Exit status: 0 stopped by SIGINT/SIGTERM, 1 runtime error, 2 usage or configuration error.

#include <unistd.h>

#include <atomic>
#include <chrono>
#include <csignal>
#include <cstdio>
#include <iostream>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <type_traits>

#include <cblox/covariance_reply_t.hpp>
#include <cblox/covariance_request_t.hpp>
#include <cblox/depth_frame_t.hpp>
#include <cblox/frame_pose_t.hpp>
#include <cblox/heartbeat_t.hpp>
#include <cblox/keyframe_pose_batch_t.hpp>
#include <cblox/keyframe_t.hpp>
#include <cblox/pose_stamped_t.hpp>
#include <cblox/stereo_pair_t.hpp>
#include <lcm/lcm-cpp.hpp>

#include "core/vocabulary/binary_vocabulary.h"
#include "daemon/config/command_line.h"
#include "daemon/config/process_main.h"
#include "daemon/config/tracker_config.h"
#include "daemon/config/yaml_config.h"
#include "daemon/lcm/messages.h"
#include "daemon/tracker/tracker_node.h"

namespace cblox {
namespace {

using Clock = std::chrono::steady_clock;

void printUsage() {
  std::cout
      << "usage: cblox-tracker [--config FILE] [--mode stereo|rgbd] [--initial-pose-from-gt]\n"
         "                     [--calibration FILE] [--vocabulary FILE|none]\n"
         "                     [--lcm-url URL] [--quiet]\n"
         "  Runs until SIGINT/SIGTERM.\n"
         "  --initial-pose-from-gt  the first keyframe takes its pose from CBLOX_GT_POSE\n"
         "                          (initial_pose: ground_truth): G = the simulator's frame\n"
         "  --calibration FILE      Kalibr/EuRoC-style camera file instead of the messages'\n"
         "  exit status: 0 stopped by signal, 1 runtime error, 2 usage/configuration\n";
}

struct Args {
  std::optional<std::string> config_file, mode, calibration, vocabulary, lcm_url;
  bool initial_pose_from_gt = false;
  bool quiet = false;
};

Args parseArgs(int argc, char** argv) {
  Args args;
  parseFlags(
      argc, argv, printUsage, {"--quiet", "--initial-pose-from-gt"},
      [&](const std::string& flag) {
        if (flag == "--quiet") args.quiet = true;
        if (flag == "--initial-pose-from-gt") args.initial_pose_from_gt = true;
      },
      [&](const std::string& flag, const std::string& value) {
        if (flag == "--config") {
          args.config_file = value;
        } else if (flag == "--mode") {
          args.mode = value;
        } else if (flag == "--calibration") {
          args.calibration = value;
        } else if (flag == "--vocabulary") {
          args.vocabulary = value;
        } else if (flag == "--lcm-url") {
          args.lcm_url = value;
        } else {
          return false;
        }
        return true;
      });
  return args;
}

TrackerProcessConfig buildConfig(const Args& args) {
  TrackerProcessConfig config = args.config_file
                                    ? loadTrackerConfig(loadYamlFile(*args.config_file))
                                    : TrackerProcessConfig{};
  if (args.mode) config.tracker.mode = parseTrackerMode(*args.mode);
  if (args.initial_pose_from_gt) config.tracker.initial_pose = InitialPose::kGroundTruth;
  if (args.calibration) {
    config.calibration_source = CalibrationSource::kFile;
    config.calibration_file = *args.calibration;
  }
  if (args.vocabulary) config.vocabulary = *args.vocabulary;
  if (args.lcm_url) config.lcm_url = *args.lcm_url;
  finishTrackerConfig(&config);
  return config;
}

// The vocabulary the config names (empty: the build's; "none": none). Throws ConfigError.
std::unique_ptr<BinaryVocabulary> loadVocabulary(const std::string& configured) {
  if (configured == "none") return nullptr;
  const std::string path = configured.empty() ? CBLOX_DEFAULT_VOCABULARY : configured;
  std::string error;
  std::optional<BinaryVocabulary> vocabulary = BinaryVocabulary::load(path, &error);
  if (!vocabulary) {
    throw ConfigError("vocabulary: " + error +
                      (configured.empty() ? " (the build's default vocabulary; build the "
                                            "cblox_vocabulary_file target or set vocabulary)"
                                          : ""));
  }
  return std::make_unique<BinaryVocabulary>(std::move(*vocabulary));
}

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

/// LCM <-> TrackerNode adapter: the handlers run on the LCM (main) thread; results are
/// published from the tracking, local mapping and loop closing threads, so every publish goes
/// through one mutex.
class TrackerLcmNode {
 public:
  TrackerLcmNode(const TrackerProcessConfig& config, lcm::LCM* lcm) : config_(config), lcm_(lcm) {}

  TrackerNode::Outputs outputs() {
    TrackerNode::Outputs out;
    out.frame_pose = [this](const FramePoseReport& r) {
      const frame_pose_t msg =
          toFramePoseMsg(r.utime, r.frame_id, r.T_G_C, toStateConstant(r.state), r.jump, 0);
      std::lock_guard<std::mutex> lock(publish_mutex_);
      lcm_->publish(config_.frame_pose_channel, &msg);
    };
    out.keyframe = [this](const KeyframeInfo& k) {
      const keyframe_t msg = toKeyframeMsg(
          k.timestamp_ns / 1000, k.id, static_cast<int64_t>(k.frame_id), k.T_G_K, k.landmark_ids);
      std::lock_guard<std::mutex> lock(publish_mutex_);
      lcm_->publish(config_.keyframe_channel, &msg);
    };
    out.keyframe_poses = [this](const KeyframePoseBatch& batch, PoseUpdateReason reason) {
      const keyframe_pose_batch_t msg =
          toKeyframePoseBatchMsg(wallUtime(), toReasonConstant(reason), batch);
      std::lock_guard<std::mutex> lock(publish_mutex_);
      lcm_->publish(config_.keyframe_poses_channel, &msg);
    };
    out.covariance_reply = [this](const KeyframeCovarianceReply& reply) {
      covariance_reply_t msg;
      msg.utime = wallUtime();
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

  void subscribe(TrackerNode* node) {
    node_ = node;
    if (config_.tracker.mode == TrackerMode::kStereo) {
      lcm_->subscribe(config_.stereo_channel, &TrackerLcmNode::onFrame<stereo_pair_t>, this);
    } else {
      lcm_->subscribe(config_.depth_channel, &TrackerLcmNode::onFrame<depth_frame_t>, this);
    }
    if (config_.tracker.initial_pose == InitialPose::kGroundTruth) {
      lcm_->subscribe(config_.ground_truth_channel, &TrackerLcmNode::onGroundTruth, this);
    }
    lcm_->subscribe(config_.covariance_request_channel, &TrackerLcmNode::onCovarianceRequest, this);
  }

  void publishHeartbeat(const TrackerStatus& s, const std::string& state) {
    heartbeat_t hb;
    hb.utime = wallUtime();
    hb.process = "cblox-tracker";
    hb.pid = static_cast<int32_t>(::getpid());
    hb.state = state;
    auto add = [&](const std::string& name, uint64_t value) {
      hb.counter_names.push_back(name);
      hb.counter_values.push_back(static_cast<int64_t>(value));
    };
    auto add_us = [&](const std::string& name, double ms) {
      hb.counter_names.push_back(name);
      hb.counter_values.push_back(static_cast<int64_t>(ms * 1000.0 + 0.5));
    };
    add("frames_received", s.frames_received);
    add("frames_processed", s.frames_processed);
    add("frames_tracked", s.frames_tracked);
    add("frames_lost", s.frames_lost);
    add("frames_not_initialized", s.frames_not_initialized);
    add("frames_dropped", s.frames_dropped);
    add("frames_rejected", s.frames_rejected);
    add("relocalizations", s.relocalizations);
    add("loop_corrected_frames", s.loop_corrected_frames);
    add("keyframes", s.keyframes);
    add("landmarks", s.landmarks);
    add("pose_batches", s.pose_batches);
    add("loops_closed", s.loops_closed);
    add("local_bundle_adjustments", s.local_bundle_adjustments);
    add("global_bundle_adjustments", s.global_bundle_adjustments);
    add("covariance_requests", s.covariance_requests);
    add("covariance_pairs_ok", s.covariance_pairs_ok);
    add("covariance_pairs_failed", s.covariance_pairs_failed);
    add("covariance_linearizations", s.covariance_linearizations);
    add("covariance_reused", s.covariance_reused);
    add_us("covariance_build_us", s.covariance_build_ms);
    add_us("covariance_solve_us", s.covariance_solve_ms);
    add_us("tracking_median_us", s.tracking_ms_median);
    add_us("tracking_p95_us", s.tracking_ms_p95);
    add_us("frame_median_us", s.frame_ms_median);
    add_us("frame_p95_us", s.frame_ms_p95);
    for (size_t i = 0; i < kNumTrackerProblems; ++i) {
      add(trackerProblemCounter(static_cast<TrackerProblem>(i)), s.problems[i]);
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

  // A CBLOX_STEREO (stereo_pair_t) or CBLOX_DEPTH (depth_frame_t) message.
  template <typename Msg>
  void onFrame(const lcm::ReceiveBuffer* rbuf, const std::string& channel) {
    Msg msg;
    if (!decode(rbuf, &msg)) {
      node_->reportProblem(TrackerProblem::kUndecodable, channel + ": message does not decode");
      return;
    }
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

  void onGroundTruth(const lcm::ReceiveBuffer* rbuf, const std::string& channel) {
    pose_stamped_t msg;
    if (!decode(rbuf, &msg)) {
      node_->reportProblem(TrackerProblem::kBadGroundTruth, channel + ": message does not decode");
      return;
    }
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

  void onCovarianceRequest(const lcm::ReceiveBuffer* rbuf, const std::string& channel) {
    covariance_request_t msg;
    if (!decode(rbuf, &msg)) {
      node_->reportProblem(TrackerProblem::kBadCovarianceRequest,
                           channel + ": message does not decode");
      return;
    }
    KeyframeCovarianceRequest request;
    request.request_id = msg.request_id;
    for (size_t k = 0; k < msg.keyframe_i.size() && k < msg.keyframe_j.size(); ++k) {
      // A negative id is no keyframe: its bit pattern as uint64 names none either, so the
      // pair is answered "not in the BA linearization".
      request.pairs.push_back(KeyframePair{static_cast<uint64_t>(msg.keyframe_i[k]),
                                           static_cast<uint64_t>(msg.keyframe_j[k])});
    }
    node_->onCovarianceRequest(std::move(request));
  }

  const TrackerProcessConfig& config_;
  lcm::LCM* lcm_;
  TrackerNode* node_ = nullptr;
  std::mutex publish_mutex_;
};

int run(const Args& args) {
  installStopHandlers();  // before the vocabulary loads: a stop then still exits 0
  const TrackerProcessConfig config = buildConfig(args);
  const TrackerNodeConfig& t = config.tracker;
  const std::unique_ptr<BinaryVocabulary> vocabulary = loadVocabulary(config.vocabulary);

  lcm::LCM lcm(config.lcm_url);
  if (!lcm.good()) {
    std::fprintf(stderr, "cblox-tracker: cannot open LCM (url '%s')\n", config.lcm_url.c_str());
    return 1;
  }
  TrackerLcmNode lcm_node(config, &lcm);
  TrackerNode node(t, vocabulary.get(), lcm_node.outputs());
  if (!args.quiet) {
    std::printf(
        "tracker: %s mode on %s, calibration from %s, initial pose %s, %d ORB features, "
        "vocabulary %s, loop closing %s\n",
        trackerModeName(t.mode),
        (t.mode == TrackerMode::kStereo ? config.stereo_channel : config.depth_channel).c_str(),
        config.calibration_source == CalibrationSource::kFile ? config.calibration_file.c_str()
                                                              : "the messages",
        initialPoseName(t.initial_pose), t.slam.frames.orb.num_features,
        vocabulary
            ? (config.vocabulary.empty() ? CBLOX_DEFAULT_VOCABULARY : config.vocabulary.c_str())
            : "none",
        vocabulary && t.slam.loop_closing_enabled ? "on" : "off");
    std::fflush(stdout);
  }
  lcm_node.subscribe(&node);
  node.start();

  const Clock::time_point start = Clock::now();
  uint64_t last_processed = 0;
  Clock::time_point last_progress = start;
  auto progress = [&](const TrackerStatus& s, const char* prefix) {
    const double dt = std::chrono::duration<double>(Clock::now() - last_progress).count();
    const double rate = dt > 0 ? static_cast<double>(s.frames_processed - last_processed) / dt : 0;
    last_processed = s.frames_processed;
    last_progress = Clock::now();
    std::printf(
        "tracker: %s%llu frames (%.1f/s): %llu tracked, %llu lost, %llu dropped, %llu "
        "rejected; %llu keyframes, %llu landmarks, %llu loops; tracking median %.1f ms, frame "
        "median %.1f ms p95 %.1f ms; %s\n",
        prefix, static_cast<unsigned long long>(s.frames_processed), rate,
        static_cast<unsigned long long>(s.frames_tracked),
        static_cast<unsigned long long>(s.frames_lost),
        static_cast<unsigned long long>(s.frames_dropped),
        static_cast<unsigned long long>(s.frames_rejected),
        static_cast<unsigned long long>(s.keyframes), static_cast<unsigned long long>(s.landmarks),
        static_cast<unsigned long long>(s.loops_closed), s.tracking_ms_median, s.frame_ms_median,
        s.frame_ms_p95, s.state.c_str());
    std::fflush(stdout);
  };

  std::vector<PeriodicTask> tasks{{config.status_period_s, 0.0, [&] {
                                     const TrackerStatus s = node.status();
                                     lcm_node.publishHeartbeat(s, s.state);
                                   }}};
  if (!args.quiet) {
    tasks.push_back(
        {config.progress_period_s, config.progress_period_s, [&] { progress(node.status(), ""); }});
  }
  const int exit_code = serveUntilStopped(lcm, "cblox-tracker", tasks);
  node.stop();  // finishes the frame in hand, then stops local mapping and loop closing
  const TrackerStatus s = node.status();
  lcm_node.publishHeartbeat(s, "stopped");
  if (!args.quiet) progress(s, "stopped: ");
  return exit_code;
}

}  // namespace
}  // namespace cblox

int main(int argc, char** argv) {
  return cblox::runProcess("cblox-tracker",
                           [&] { return cblox::run(cblox::parseArgs(argc, argv)); });
}
