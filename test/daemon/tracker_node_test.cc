// The tracker process's parts without LCM: TrackerNode on simulated stereo (poses against
// the exact trajectory, keyframes, input checks), the image check, the ground-truth buffer
// and the stereo / RGB-D message decoders.

#include "daemon/tracker/tracker_node.h"

#include <sys/resource.h>

#include <cerrno>
#include <chrono>
#include <climits>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <map>
#include <mutex>
#include <string>
#include <thread>
#include <vector>

#include <gtest/gtest.h>

#include "daemon/common/lcm_messages.h"
#include "daemon/tracker/ground_truth_buffer.h"
#include "daemon/tracker/image_check.h"
#include "daemon/tracker/tracker_input.h"
#include "drivers/open_frame_source.h"

namespace cblox {
namespace {

/// Everything a TrackerNode reports, collected thread-safely.
struct Collected {
  std::mutex mutex;
  std::vector<FramePoseReport> poses;
  std::vector<KeyframeInfo> keyframes;
  std::vector<std::pair<KeyframePoseBatch, PoseUpdateReason>> batches;
  std::vector<std::string> log;
  std::vector<KeyframeCovarianceReply> covariance_replies;

  TrackerNode::Outputs outputs() {
    TrackerNode::Outputs out;
    out.covariance_reply = [this](const KeyframeCovarianceReply& r) {
      std::lock_guard<std::mutex> lock(mutex);
      covariance_replies.push_back(r);
    };
    out.frame_pose = [this](const FramePoseReport& r) {
      std::lock_guard<std::mutex> lock(mutex);
      poses.push_back(r);
    };
    out.keyframe = [this](const KeyframeInfo& k) {
      std::lock_guard<std::mutex> lock(mutex);
      keyframes.push_back(k);
    };
    out.keyframe_poses = [this](const KeyframePoseBatch& b, PoseUpdateReason reason) {
      std::lock_guard<std::mutex> lock(mutex);
      batches.emplace_back(b, reason);
    };
    out.log = [this](const std::string& line) {
      std::lock_guard<std::mutex> lock(mutex);
      log.push_back(line);
    };
    return out;
  }
};

std::unique_ptr<FrameSource> simRoom(size_t frames, const PinholeIntrinsics& rig) {
  SourceConfig options;
  options.trajectory = "loop";
  options.max_frames = frames;
  options.sim.renderer.rig.stereo = rig;
  std::string error;
  std::unique_ptr<FrameSource> source = openFrameSource("sim:room", options, &error);
  EXPECT_NE(source, nullptr) << error;
  return source;
}

TrackerFrame toTrackerFrame(const CaptureFrame& frame, const SourceInfo& info) {
  const stereo_pair_t msg = toStereoPairMsg(frame, info, frame.timestamp_ns / 1000);
  TrackerFrame out;
  TrackerProblem problem;
  std::string error;
  EXPECT_TRUE(decodeStereoPair(msg, &out, &problem, &error)) << error;
  return out;
}

// The half-size EuRoC-like rig: a quarter of the work of 752x480.
const PinholeIntrinsics kHalfRig{229.0, 229.0, 187.5, 119.5, 376, 240};
const PinholeIntrinsics kFullRig{458.0, 458.0, 375.5, 239.5, 752, 480};

TEST(TrackerNodeTest, TracksRgbdFramesOfTheSimulatedRoom) {
  constexpr size_t kFrames = 60;
  auto source = simRoom(kFrames, kFullRig);
  ASSERT_NE(source, nullptr);
  TrackerNodeConfig config;
  config.mode = TrackerMode::kRgbd;
  config.initial_pose = InitialPose::kGroundTruth;
  config.local_mapping_niceness = 7;  // no other thread of this process has 7
  Collected out;
  TrackerNode node(config, nullptr, out.outputs());
  node.start();
  // Before the map exists a covariance request fails at once, pair by pair.
  node.onCovarianceRequest({1, {{1, 0}, {2, 0}}});
  {
    std::lock_guard<std::mutex> lock(out.mutex);
    ASSERT_EQ(out.covariance_replies.size(), 1u);
    ASSERT_EQ(out.covariance_replies[0].results.size(), 2u);
    EXPECT_FALSE(out.covariance_replies[0].results[1].ok);
    EXPECT_NE(out.covariance_replies[0].results[1].error.find("no map yet"), std::string::npos);
  }
  std::map<int64_t, Transformationd> truth;
  CaptureFrame frame;
  std::string error;
  while (source->next(&frame, &error) == FrameSource::Status::kFrame) {
    truth[frame.frame_id] = *frame.T_G_C;
    const int64_t utime = frame.timestamp_ns / 1000;
    node.onGroundTruth(frame.frame_id, utime, *frame.T_G_C);
    TrackerFrame input;
    TrackerProblem problem;
    ASSERT_TRUE(decodeRgbdFrame(
        toDepthFrameMsg(frame, source->info(), utime, DepthEncoding::kUint16Millimetres), &input,
        &problem, &error))
        << error;
    ASSERT_TRUE(node.onFrame(std::move(input)));
    ASSERT_TRUE(node.waitUntilIdle(std::chrono::seconds(20)));  // no frame dropped
  }
  // The local mapping thread runs at its niceness (no vocabulary: no loop closing thread).
  int at_seven = 0;
  for (const auto& entry : std::filesystem::directory_iterator("/proc/self/task")) {
    errno = 0;
    const int nice =
        getpriority(PRIO_PROCESS, static_cast<id_t>(std::stol(entry.path().filename().string())));
    at_seven += errno == 0 && nice == 7;
  }
  EXPECT_EQ(at_seven, 1);
  // With the map: the service thread answers from it.
  ASSERT_GE(out.keyframes.size(), 3u);
  const uint64_t last = out.keyframes.back().id,
                 before = out.keyframes[out.keyframes.size() - 2].id;
  node.onCovarianceRequest({2, {{last, before}}});
  for (int i = 0; i < 1000; ++i) {
    {
      std::lock_guard<std::mutex> lock(out.mutex);
      if (out.covariance_replies.size() == 2) break;
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
  }
  node.stop();
  {
    std::lock_guard<std::mutex> lock(out.mutex);
    ASSERT_EQ(out.covariance_replies.size(), 2u);
    const KeyframeCovarianceReply& reply = out.covariance_replies[1];
    EXPECT_EQ(reply.request_id, 2);
    ASSERT_EQ(reply.results.size(), 1u);
    ASSERT_TRUE(reply.results[0].ok) << reply.results[0].error;
    EXPECT_GT(reply.results[0].q, 0.0);
    EXPECT_EQ(node.status().covariance_pairs_ok, 1u);
  }
  ASSERT_EQ(out.poses.size(), kFrames);
  double max_translation_m = 0.0, max_rotation_deg = 0.0;
  for (const FramePoseReport& r : out.poses) {
    ASSERT_EQ(r.state, FramePoseState::kOk) << "frame " << r.frame_id << ": " << r.reason;
    EXPECT_FALSE(r.jump);
    const Transformationd& T_true = truth.at(r.frame_id);
    max_translation_m =
        std::max(max_translation_m, (r.T_G_C->translation() - T_true.translation()).norm());
    max_rotation_deg = std::max(
        max_rotation_deg, r.T_G_C->rotation().angularDistance(T_true.rotation()) * 180.0 / M_PI);
  }
  std::printf("rgbd: %zu frames, %zu keyframes, max error %.4f m %.3f deg\n", out.poses.size(),
              out.keyframes.size(), max_translation_m, max_rotation_deg);
  // The map starts at the first frame's exact pose.
  EXPECT_TRUE(out.poses.front().T_G_C->isApprox(truth.at(0), 1e-9));
  ASSERT_FALSE(out.keyframes.empty());
  EXPECT_TRUE(out.keyframes.front().T_G_K.isApprox(truth.at(0), 1e-9));
  EXPECT_GE(out.keyframes.front().landmark_ids.size(), 100u);
  // Measured: 0.0065 m and 0.184 deg at most.
  EXPECT_LT(max_translation_m, 0.015);
  EXPECT_LT(max_rotation_deg, 0.4);
  const TrackerStatus s = node.status();
  EXPECT_EQ(s.frames_received, kFrames);
  EXPECT_EQ(s.frames_tracked, kFrames);
  EXPECT_EQ(s.keyframes, out.keyframes.size());
  EXPECT_EQ(s.pose_batches, out.batches.size());
  EXPECT_GT(s.landmarks, 0u);
  EXPECT_EQ(s.state, "tracking");
  // Local mapping's counters reach the status (and so the heartbeat): its BAs moved the
  // keyframes (the pose batches), and its thread's CPU was counted.
  EXPECT_GT(s.local_bundle_adjustments, 0u);
  EXPECT_LE(s.local_bundle_adjustments_interrupted, s.local_bundle_adjustments);
  EXPECT_GT(s.local_mapping_cpu_ms, 0.0);
  EXPECT_EQ(s.essential_graphs_failed, 0u);
}

TEST(TrackerNodeTest, GroundTruthStartWaitsForThePoseOfItsFrame) {
  auto source = simRoom(2, kHalfRig);
  ASSERT_NE(source, nullptr);
  TrackerNodeConfig config;
  config.initial_pose = InitialPose::kGroundTruth;
  config.ground_truth_wait_s = 0.05;
  config.slam.tracker.min_features_to_initialize = 200;
  Collected out;
  TrackerNode node(config, nullptr, out.outputs());
  node.start();
  CaptureFrame frame;
  std::string error;
  // Frame 0 without its ground truth (another frame's does not count).
  ASSERT_EQ(source->next(&frame, &error), FrameSource::Status::kFrame);
  node.onGroundTruth(7, 123, *frame.T_G_C);
  ASSERT_TRUE(node.onFrame(toTrackerFrame(frame, source->info())));
  ASSERT_TRUE(node.waitUntilIdle(std::chrono::seconds(5)));
  ASSERT_EQ(out.poses.size(), 1u);
  EXPECT_EQ(out.poses[0].state, FramePoseState::kNotInitialized);
  EXPECT_FALSE(out.poses[0].T_G_C.has_value());
  EXPECT_NE(out.poses[0].reason.find("no ground-truth pose"), std::string::npos);
  EXPECT_EQ(node.status().problem(TrackerProblem::kNoGroundTruth), 1u);
  EXPECT_EQ(node.status().frames_not_initialized, 1u);
  EXPECT_EQ(node.status().state.rfind("not initialized: no ground-truth pose", 0), 0u);
  // Frame 1 with it (matched by frame id): the map starts there, at that pose.
  ASSERT_EQ(source->next(&frame, &error), FrameSource::Status::kFrame);
  node.onGroundTruth(frame.frame_id, frame.timestamp_ns / 1000, *frame.T_G_C);
  ASSERT_TRUE(node.onFrame(toTrackerFrame(frame, source->info())));
  ASSERT_TRUE(node.waitUntilIdle(std::chrono::seconds(5)));
  ASSERT_EQ(out.poses.size(), 2u);
  EXPECT_EQ(out.poses[1].state, FramePoseState::kOk) << out.poses[1].reason;
  EXPECT_FALSE(out.poses[1].jump);
  ASSERT_TRUE(out.poses[1].T_G_C.has_value());
  EXPECT_TRUE(out.poses[1].T_G_C->isApprox(*frame.T_G_C, 1e-9));
  node.stop();
}

// `frames` frames of the room arrive before the tracking thread runs; then it runs until
// idle. The poses it published and its status.
std::pair<std::vector<FramePoseReport>, TrackerStatus> trackQueuedFrames(size_t frames,
                                                                         TrackerNodeConfig config) {
  auto source = simRoom(frames, kHalfRig);
  EXPECT_NE(source, nullptr);
  if (!source) return {};
  config.slam.tracker.min_features_to_initialize = 200;
  Collected out;
  TrackerNode node(config, nullptr, out.outputs());
  CaptureFrame frame;
  std::string error;
  while (source->next(&frame, &error) == FrameSource::Status::kFrame) {
    EXPECT_TRUE(node.onFrame(toTrackerFrame(frame, source->info())));
  }
  node.start();
  EXPECT_TRUE(node.waitUntilIdle(std::chrono::seconds(10)));
  node.stop();
  return {out.poses, node.status()};
}

// With catch_up false and room for one frame, only the newest of three is tracked.
TEST(TrackerNodeTest, NewestFrameWinsWhenTheTrackerIsBehind) {
  TrackerNodeConfig config;
  config.catch_up = false;
  config.queue_capacity = 1;
  const auto [poses, s] = trackQueuedFrames(3, config);
  ASSERT_EQ(poses.size(), 1u);
  EXPECT_EQ(poses[0].frame_id, 2);
  EXPECT_EQ(poses[0].state, FramePoseState::kOk) << poses[0].reason;
  EXPECT_EQ(s.frames_received, 3u);
  EXPECT_EQ(s.frames_dropped, 2u);
  EXPECT_EQ(s.frames_processed, 1u);
  EXPECT_EQ(s.frames_rejected, 0u);
}

// The default: frames that wait while the tracker is behind are all tracked, in order; only
// those pushed out of the full queue (4) are dropped.
TEST(TrackerNodeTest, TheTrackerCatchesUpOnTheWaitingFramesInOrder) {
  const TrackerNodeConfig config;
  ASSERT_TRUE(config.catch_up);
  ASSERT_EQ(config.queue_capacity, 4u);
  const auto [poses, s] = trackQueuedFrames(6, config);
  ASSERT_EQ(poses.size(), 4u);
  for (size_t i = 0; i < 4; ++i) {
    EXPECT_EQ(poses[i].frame_id, static_cast<int64_t>(i + 2));
    EXPECT_EQ(poses[i].state, FramePoseState::kOk) << poses[i].reason;
  }
  EXPECT_EQ(s.frames_received, 6u);
  EXPECT_EQ(s.frames_dropped, 2u);
  EXPECT_EQ(s.frames_processed, 4u);
}

/// A small frame with a valid message calibration (not tracked in these tests).
TrackerFrame smallFrame(int64_t id, int64_t utime, double fx = 50.0, double baseline = 0.1) {
  TrackerFrame frame;
  frame.frame_id = id;
  frame.utime = utime;
  frame.image = GrayImage(64, 48, 100);
  frame.right = GrayImage(64, 48, 100);
  frame.calibration =
      RectifiedStereoCalibration{PinholeIntrinsics{fx, 50.0, 31.5, 23.5, 64, 48}, baseline, {}};
  return frame;
}

TEST(TrackerNodeTest, RejectsBadCalibrationSizeChangesAndDisorderCountingEachKind) {
  TrackerNodeConfig config;
  config.queue_capacity = 16;
  Collected out;
  TrackerNode node(config, nullptr, out.outputs());  // not started: frames only queue
  TrackerFrame no_calibration = smallFrame(0, 1000);
  no_calibration.calibration.reset();
  no_calibration.calibration_error = "stereo pair: not rectified";
  EXPECT_FALSE(node.onFrame(no_calibration));
  TrackerFrame small = smallFrame(0, 1000);
  small.image = GrayImage(32, 24);
  EXPECT_FALSE(node.onFrame(small));                           // wrong_size: not the calibration's
  EXPECT_TRUE(node.onFrame(smallFrame(1, 2000)));              // fixes the camera
  EXPECT_FALSE(node.onFrame(smallFrame(2, 3000, 51.0)));       // fx changed
  EXPECT_FALSE(node.onFrame(smallFrame(3, 4000, 50.0, 0.2)));  // baseline changed
  // Frame ids back while time goes on: a capture restarted on a live clock, same map.
  EXPECT_TRUE(node.onFrame(smallFrame(1, 5000)));
  EXPECT_FALSE(node.onFrame(smallFrame(4, 2000)));  // time not increasing (3 ms back)
  EXPECT_FALSE(node.onFrame(smallFrame(5, 5000)));  // time not increasing
  EXPECT_TRUE(node.onFrame(smallFrame(4, 5001)));
  node.reportProblem(TrackerProblem::kUndecodable, "CBLOX_STEREO: message does not decode");
  node.reportProblem(TrackerProblem::kBadGroundTruth, "not a frame");

  const TrackerStatus s = node.status();
  EXPECT_EQ(s.frames_received, 10u);  // the ground-truth problem is no frame
  EXPECT_EQ(s.source_restarts, 1u);
  EXPECT_EQ(s.map_epoch, 0);  // time never went back by 2 s: the same map
  EXPECT_EQ(s.frames_rejected, 7u);
  EXPECT_EQ(s.problem(TrackerProblem::kBadCalibration), 1u);
  EXPECT_EQ(s.problem(TrackerProblem::kWrongSize), 1u);
  EXPECT_EQ(s.problem(TrackerProblem::kCalibrationChanged), 2u);
  EXPECT_EQ(s.problem(TrackerProblem::kOutOfOrder), 2u);
  EXPECT_EQ(s.problem(TrackerProblem::kUndecodable), 1u);
  EXPECT_EQ(s.problem(TrackerProblem::kBadGroundTruth), 1u);
  EXPECT_EQ(s.state, "waiting for frames");
  // Logged once per kind: the second calibration change and out-of-order frame are not.
  std::lock_guard<std::mutex> lock(out.mutex);
  ASSERT_EQ(out.log.size(), 7u);
  EXPECT_EQ(out.log[0], "bad_calibration: frame 0 (1000 us): stereo pair: not rectified");
  EXPECT_EQ(out.log[1], "wrong_size: frame 0 (1000 us): image 32x24, the calibration is 64x48");
  EXPECT_EQ(out.log[2].rfind("calibration_changed: frame 2 (3000 us): calibration 64x48 fx "
                             "51.000",
                             0),
            0u)
      << out.log[2];
  EXPECT_EQ(out.log[3],
            "frame 1 (5000 us): frame ids went back (from 1) while time went on: the capture "
            "restarted; tracking continues in the same map");
  EXPECT_EQ(out.log[4],
            "out_of_order: frame 4 (2000 us): not after the previous frame 1 (5000 us)");
}

// Time stamps from the bus may be 2^63 apart: a step back that large is a restart, counted,
// not a signed overflow (found by fuzz_tracker_lcm).
TEST(TrackerNodeTest, TimeStampsAtTheExtremesAreCountedNotOverflowed) {
  TrackerNodeConfig config;
  config.queue_capacity = 16;
  Collected out;
  TrackerNode node(config, nullptr, out.outputs());  // not started: frames only queue
  EXPECT_TRUE(node.onFrame(smallFrame(1, 4035225266124964416)));
  EXPECT_TRUE(node.onFrame(smallFrame(2, -5548433881925943296)));  // back by 9.6e12 s
  EXPECT_TRUE(node.onFrame(smallFrame(3, INT64_MAX)));
  EXPECT_TRUE(node.onFrame(smallFrame(4, INT64_MIN + 1)));   // back by 2^64 - 2 us
  EXPECT_FALSE(node.onFrame(smallFrame(5, INT64_MIN + 1)));  // not after it
  const TrackerStatus s = node.status();
  EXPECT_EQ(s.source_restarts, 2u);
  EXPECT_EQ(s.problem(TrackerProblem::kOutOfOrder), 1u);
  std::lock_guard<std::mutex> lock(out.mutex);
  ASSERT_FALSE(out.log.empty());
  EXPECT_NE(out.log[0].find("time went back by 9583659148050.9"), std::string::npos) << out.log[0];
}

TEST(TrackerNodeTest, ATimeStepBackStartsANewMapInTheNextEpoch) {
  TrackerNodeConfig config;
  config.mode = TrackerMode::kRgbd;
  config.initial_pose = InitialPose::kGroundTruth;
  config.restart_after_backwards_s = 2.0;
  Collected out;
  TrackerNode node(config, nullptr, out.outputs());
  node.start();
  const auto play = [&](size_t frames) {
    auto source = simRoom(frames, kFullRig);
    ASSERT_NE(source, nullptr);
    CaptureFrame frame;
    std::string error;
    while (source->next(&frame, &error) == FrameSource::Status::kFrame) {
      const int64_t utime = frame.timestamp_ns / 1000;
      node.onGroundTruth(frame.frame_id, utime, *frame.T_G_C);
      TrackerFrame input;
      TrackerProblem problem;
      ASSERT_TRUE(decodeRgbdFrame(
          toDepthFrameMsg(frame, source->info(), utime, DepthEncoding::kUint16Millimetres), &input,
          &problem, &error))
          << error;
      ASSERT_TRUE(node.onFrame(std::move(input)));
      ASSERT_TRUE(node.waitUntilIdle(std::chrono::seconds(20)));
    }
  };
  play(50);  // 0 .. 2.45 s
  EXPECT_EQ(node.status().map_epoch, 0);
  play(5);  // from 0 s again: 2.45 s back
  const TrackerStatus s = node.status();
  EXPECT_EQ(s.map_epoch, 1);
  EXPECT_EQ(s.source_restarts, 1u);
  EXPECT_EQ(s.frames_rejected, 0u);
  {
    std::lock_guard<std::mutex> lock(out.mutex);
    ASSERT_EQ(out.poses.size(), 55u);
    for (size_t i = 0; i < 50; ++i) EXPECT_EQ(out.poses[i].map_epoch, 0);
    // The new map's first pose says so (a jump); the rest track on in epoch 1.
    EXPECT_EQ(out.poses[50].state, FramePoseState::kMapReset) << out.poses[50].reason;
    EXPECT_TRUE(out.poses[50].jump);
    for (size_t i = 50; i < 55; ++i) EXPECT_EQ(out.poses[i].map_epoch, 1);
    for (size_t i = 51; i < 55; ++i) EXPECT_EQ(out.poses[i].state, FramePoseState::kOk);
  }
  // A covariance request about the old map fails pair by pair, naming the epochs.
  node.onCovarianceRequest({7, {{1, 0}}}, 0);
  node.stop();
  std::lock_guard<std::mutex> lock(out.mutex);
  ASSERT_EQ(out.covariance_replies.size(), 1u);
  ASSERT_EQ(out.covariance_replies[0].results.size(), 1u);
  EXPECT_FALSE(out.covariance_replies[0].results[0].ok);
  EXPECT_NE(out.covariance_replies[0].results[0].error.find(
                "keyframes of map epoch 0; the tracker's map is epoch 1"),
            std::string::npos)
      << out.covariance_replies[0].results[0].error;
}

TEST(TrackerNodeTest, ConfiguredCalibrationOverridesTheMessages) {
  TrackerNodeConfig config;
  config.queue_capacity = 16;
  config.calibration =
      RectifiedStereoCalibration{PinholeIntrinsics{50.0, 50.0, 31.5, 23.5, 64, 48}, 0.1, {}};
  Collected out;
  TrackerNode node(config, nullptr, out.outputs());
  TrackerFrame no_calibration = smallFrame(0, 1000);
  no_calibration.calibration.reset();
  EXPECT_TRUE(node.onFrame(no_calibration));
  EXPECT_TRUE(node.onFrame(smallFrame(1, 2000, 80.0)));  // the message's fx is not used
  TrackerFrame other_size = smallFrame(2, 3000);
  other_size.image = GrayImage(80, 48);
  other_size.right = GrayImage(80, 48);
  other_size.calibration->intrinsics.width = 80;
  EXPECT_FALSE(node.onFrame(other_size));
  EXPECT_EQ(node.status().problem(TrackerProblem::kWrongSize), 1u);
}

TEST(TrackerNodeTest, InvalidConfigThrows) {
  TrackerNodeConfig config;
  config.queue_capacity = 0;
  EXPECT_THROW(TrackerNode(config, nullptr, {}), std::invalid_argument);
  config = TrackerNodeConfig{};
  config.slam.frames.orb.num_features = 0;
  EXPECT_THROW(TrackerNode(config, nullptr, {}), std::invalid_argument);
  config = TrackerNodeConfig{};
  config.loop_closing_niceness = 20;
  EXPECT_NE(config.validate().find("loop_closing_niceness"), std::string::npos);
  EXPECT_THROW(TrackerNode(config, nullptr, {}), std::invalid_argument);
}

TEST(ImageCheckTest, FindsDarkSaturatedAndTexturelessImages) {
  const ImageCheckConfig config;
  auto check = [&](const GrayImage& image) { return checkImage(image, config, "left image"); };
  GrayImage black(100, 80, 3);
  auto r = check(black);
  ASSERT_TRUE(r.has_value());
  EXPECT_EQ(r->defect, ImageDefect::kDark);
  EXPECT_EQ(r->description, "left image is dark: 100.0% of pixels <= 10");
  r = check(GrayImage(100, 80, 250));
  ASSERT_TRUE(r.has_value());
  EXPECT_EQ(r->defect, ImageDefect::kSaturated);
  EXPECT_EQ(r->description, "left image is saturated: 100.0% of pixels >= 245");
  // A ramp of one grey level per column: horizontal differences 1, vertical 0 -> mean 0.5.
  GrayImage ramp(100, 80);
  for (int v = 0; v < 80; ++v) {
    for (int u = 0; u < 100; ++u) ramp(u, v) = static_cast<uint8_t>(50 + u);
  }
  r = check(ramp);
  ASSERT_TRUE(r.has_value());
  EXPECT_EQ(r->defect, ImageDefect::kTextureless);
  EXPECT_EQ(r->description, "left image is textureless: mean gradient 0.50 < 1.00 grey levels");
  // Two grey levels per column: mean 1.0, not below the threshold.
  for (int v = 0; v < 80; ++v) {
    for (int u = 0; u < 100; ++u) ramp(u, v) = static_cast<uint8_t>(20 + 2 * u);
  }
  EXPECT_FALSE(check(ramp).has_value());
  // 96% of the pixels dark (every 25th bright): dark; 94%: not.
  GrayImage mostly_dark(100, 80, 0);
  for (size_t i = 0; i < mostly_dark.data.size(); i += 50) mostly_dark.data[i] = 200;
  EXPECT_EQ(check(mostly_dark)->defect, ImageDefect::kDark);
  EXPECT_TRUE(check(GrayImage()).has_value());  // empty
  ImageCheckConfig off;
  off.enabled = false;
  EXPECT_FALSE(checkImage(black, off, "x").has_value());
  // A rendered view of the textured room passes.
  auto source = simRoom(1, kHalfRig);
  ASSERT_NE(source, nullptr);
  CaptureFrame frame;
  std::string error;
  ASSERT_EQ(source->next(&frame, &error), FrameSource::Status::kFrame);
  EXPECT_FALSE(check(frame.left).has_value());
}

TEST(ImageCheckTest, ValidateNamesTheField) {
  ImageCheckConfig c;
  c.dark_level = 250;
  EXPECT_NE(c.validate().find("dark_level"), std::string::npos);
  c = ImageCheckConfig{};
  c.max_fraction = 1.5;
  EXPECT_NE(c.validate().find("max_fraction"), std::string::npos);
  c = ImageCheckConfig{};
  c.min_mean_gradient = -1.0;
  EXPECT_NE(c.validate().find("min_mean_gradient"), std::string::npos);
  EXPECT_TRUE(ImageCheckConfig{}.validate().empty());
}

TEST(GroundTruthBufferTest, MatchesByFrameIdOrTimeAndKeepsTheNewest) {
  GroundTruthBuffer buffer(2);
  const auto at = [](double x) {
    return Transformationd(Eigen::Quaterniond::Identity(), Eigen::Vector3d(x, 0, 0));
  };
  buffer.add(5, 500, at(5));
  buffer.add(-1, 600, at(6));  // no frame id: matched by time
  const auto none = std::chrono::milliseconds(0);
  ASSERT_TRUE(buffer.waitFor(5, 999, none).has_value());
  EXPECT_EQ(buffer.waitFor(5, 999, none)->translation().x(), 5.0);
  EXPECT_EQ(buffer.waitFor(6, 600, none)->translation().x(), 6.0);
  EXPECT_FALSE(buffer.waitFor(6, 601, none).has_value());
  buffer.add(7, 700, at(7));  // capacity 2: frame 5 goes
  EXPECT_FALSE(buffer.waitFor(5, 500, none).has_value());
  // A pose that arrives while waiting is found; a missing one times out.
  std::thread adder([&] {
    std::this_thread::sleep_for(std::chrono::milliseconds(30));
    buffer.add(8, 800, at(8));
  });
  const auto start = std::chrono::steady_clock::now();
  const auto found = buffer.waitFor(8, 800, std::chrono::seconds(5));
  adder.join();
  ASSERT_TRUE(found.has_value());
  EXPECT_EQ(found->translation().x(), 8.0);
  EXPECT_LT(std::chrono::steady_clock::now() - start, std::chrono::seconds(4));
  const auto before = std::chrono::steady_clock::now();
  EXPECT_FALSE(buffer.waitFor(9, 900, std::chrono::milliseconds(50)).has_value());
  EXPECT_GE(std::chrono::steady_clock::now() - before, std::chrono::milliseconds(50));
  buffer.interrupt();
  EXPECT_FALSE(buffer.waitFor(9, 900, std::chrono::seconds(10)).has_value());  // at once
}

TEST(TrackerInputTest, DecodesStereoPairsAndNamesWhatIsWrong) {
  auto source = simRoom(1, kHalfRig);
  ASSERT_NE(source, nullptr);
  CaptureFrame frame;
  std::string error;
  ASSERT_EQ(source->next(&frame, &error), FrameSource::Status::kFrame);
  const stereo_pair_t msg = toStereoPairMsg(frame, source->info(), 4242);
  TrackerFrame out;
  TrackerProblem problem = TrackerProblem::kCount;
  ASSERT_TRUE(decodeStereoPair(msg, &out, &problem, &error)) << error;
  EXPECT_EQ(out.utime, 4242);
  EXPECT_EQ(out.image.data, frame.left.data);
  EXPECT_EQ(out.right.data, frame.right.data);
  ASSERT_TRUE(out.calibration.has_value());
  EXPECT_EQ(out.calibration->intrinsics.fx, kHalfRig.fx);
  EXPECT_EQ(out.calibration->baseline_m, source->info().stereo->baseline_m);

  stereo_pair_t bad = msg;  // a bad calibration is left to the caller
  bad.T_L_R.position[1] = 0.01;
  ASSERT_TRUE(decodeStereoPair(bad, &out, &problem, &error));
  EXPECT_FALSE(out.calibration.has_value());
  EXPECT_NE(out.calibration_error.find("T_L_R"), std::string::npos) << out.calibration_error;

  bad = msg;
  bad.right.pixel_format = 42;
  EXPECT_FALSE(decodeStereoPair(bad, &out, &problem, &error));
  EXPECT_EQ(problem, TrackerProblem::kBadImage);
  EXPECT_EQ(error, "right: image right: unknown pixel_format 42");
  bad = msg;
  bad.left.utime += 1;
  EXPECT_FALSE(decodeStereoPair(bad, &out, &problem, &error));
  EXPECT_EQ(problem, TrackerProblem::kTimestampMismatch);
  EXPECT_EQ(error, "left image at 4243 us, right at 4242 us");
  bad = msg;
  bad.right = toImageMsg(GrayImage(10, 10), 4242, "right");
  EXPECT_FALSE(decodeStereoPair(bad, &out, &problem, &error));
  EXPECT_EQ(problem, TrackerProblem::kWrongSize);
  EXPECT_EQ(error, "left image 376x240, right image 10x10");
  EXPECT_STREQ(trackerProblemName(TrackerProblem::kTimestampMismatch), "timestamp_mismatch");
  EXPECT_EQ(trackerProblemCounter(TrackerProblem::kOutOfOrder), "rejected_out_of_order");
  EXPECT_EQ(trackerProblemCounter(TrackerProblem::kDarkImage), "untracked_dark_image");
  EXPECT_EQ(trackerProblemCounter(TrackerProblem::kBadGroundTruth), "rejected_bad_ground_truth");
}

TEST(TrackerInputTest, DecodesRgbdFramesWithColourAndDepthRange) {
  auto source = simRoom(1, kHalfRig);
  ASSERT_NE(source, nullptr);
  CaptureFrame frame;
  std::string error;
  ASSERT_EQ(source->next(&frame, &error), FrameSource::Status::kFrame);
  depth_frame_t msg = toDepthFrameMsg(frame, source->info(), 77, DepthEncoding::kFloat32Metres);
  msg.max_depth_m = 3.0f;
  TrackerFrame out;
  TrackerProblem problem = TrackerProblem::kCount;
  ASSERT_TRUE(decodeRgbdFrame(msg, &out, &problem, &error)) << error;
  ASSERT_TRUE(out.calibration.has_value());
  EXPECT_EQ(out.calibration->intrinsics.width, kHalfRig.width);
  EXPECT_EQ(out.calibration->baseline_m, 0.0);
  EXPECT_TRUE(out.right.empty());
  size_t beyond = 0, kept = 0;
  for (size_t i = 0; i < frame.depth.data.size(); ++i) {
    const float d = frame.depth.data[i];
    if (d > 3.0f) {
      ++beyond;
      EXPECT_EQ(out.depth.data[i], 0.0f);
    } else if (d > 0.0f) {
      ++kept;
      EXPECT_EQ(out.depth.data[i], d);
    }
  }
  EXPECT_GT(beyond, 0u);
  EXPECT_GT(kept, 0u);
  depth_frame_t bad = msg;
  bad.has_color = false;
  EXPECT_FALSE(decodeRgbdFrame(bad, &out, &problem, &error));
  EXPECT_EQ(problem, TrackerProblem::kBadImage);
  bad = msg;
  bad.color.utime = 78;
  EXPECT_FALSE(decodeRgbdFrame(bad, &out, &problem, &error));
  EXPECT_EQ(problem, TrackerProblem::kTimestampMismatch);
  bad = msg;
  bad.color = toImageMsg(ColorImage(8, 8), 77, "depth");
  EXPECT_FALSE(decodeRgbdFrame(bad, &out, &problem, &error));
  EXPECT_EQ(problem, TrackerProblem::kWrongSize);
}

}  // namespace
}  // namespace cblox
