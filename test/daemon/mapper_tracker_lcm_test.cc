// Multi-process test of cblox-mapper in tracker mode: this process plays the tracker (frame
// poses, keyframes with landmark ids, covariance replies, a keyframe pose batch) and the
// capture (simulated depth frames), and sends malformed messages; the mapper must integrate
// the frames, ask for the covariance of its covisible subvolumes and fuse them when the
// answer is certain enough, apply the batch, count every bad input by kind and keep running. Runs
// in a private network namespace (scripts/netns-run.sh; ctest does this).

#include <signal.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <fstream>
#include <map>
#include <optional>
#include <string>
#include <thread>
#include <vector>

#include <gtest/gtest.h>
#include <cblox/command_reply_t.hpp>
#include <cblox/command_t.hpp>
#include <cblox/covariance_reply_t.hpp>
#include <cblox/covariance_request_t.hpp>
#include <cblox/frame_pose_t.hpp>
#include <cblox/keyframe_pose_batch_t.hpp>
#include <cblox/keyframe_t.hpp>
#include <lcm/lcm-cpp.hpp>

#include "daemon/common/lcm_messages.h"
#include "drivers/open_frame_source.h"
#include "test/test_support/spawn.h"
#include "test/test_support/temp_dir.h"

namespace cblox {
namespace {

const char* kUrl = "udpm://239.255.76.67:7667?ttl=0&recv_buf_size=4194304";

struct Replies {
  std::optional<command_reply_t> reply;
  int64_t id = 0;
  void onReply(const lcm::ReceiveBuffer*, const std::string&, const command_reply_t* m) {
    if (m->command_id == id) reply = *m;
  }
};

std::map<std::string, std::string> statusOf(lcm::LCM* lcm, Replies* replies, int64_t id) {
  command_t cmd;
  cmd.utime = 0;
  cmd.command_id = id;
  cmd.sender = "test";
  cmd.name = "status";
  cmd.num_args = 0;
  replies->id = id;
  replies->reply.reset();
  lcm->publish("CBLOX_CMD", &cmd);
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(10);
  while (!replies->reply && std::chrono::steady_clock::now() < deadline) lcm->handleTimeout(50);
  std::map<std::string, std::string> values;
  if (replies->reply) {
    for (int i = 0; i < replies->reply->num_values; ++i) {
      values[replies->reply->value_keys[i]] = replies->reply->values[i];
    }
  }
  return values;
}

/// Plays the tracker's covariance service: every pair is certain (q = 1e6).
struct CovarianceResponder {
  lcm::LCM* lcm = nullptr;
  std::vector<covariance_request_t> requests;
  void onRequest(const lcm::ReceiveBuffer*, const std::string&, const covariance_request_t* m) {
    requests.push_back(*m);
    covariance_reply_t reply{};
    reply.utime = m->utime;
    reply.request_id = m->request_id;
    for (int k = 0; k < m->num_pairs; ++k) {
      covariance_pair_t pair{};
      pair.keyframe_i = m->keyframe_i[k];
      pair.keyframe_j = m->keyframe_j[k];
      pair.ok = true;
      for (int d = 0; d < 6; ++d) pair.sigma_i_given_j[7 * d] = 1e-6;
      pair.q = 1e6;
      reply.pairs.push_back(pair);
    }
    reply.num_pairs = static_cast<int32_t>(reply.pairs.size());
    lcm->publish("CBLOX_COV_REPLY", &reply);
  }
};

int64_t value(const std::map<std::string, std::string>& values, const std::string& key) {
  const auto it = values.find(key);
  return it == values.end() ? 0 : std::stoll(it->second);
}

TEST(MapperTrackerLcmTest, IntegratesTrackerPosesAppliesBatchesAndCountsBadInput) {
  test::TempDir dir("cblox_mapper_tracker");
  // Two keyframes per subvolume: keyframes 0, 5 | 10, 15 | 20, 25 (frames every 5).
  const std::string config = (dir.path() / "mapper.yaml").string();
  {
    std::ofstream out(config);
    out << "subvolumes: {max_keyframes_per_subvolume: 2}\n";
  }
  const std::vector<std::string> args = {
      CBLOX_MAPPER_EXE,    "--config",  config, "--pose-source", "tracker", "--output-dir",
      dir.path().string(), "--lcm-url", kUrl,   "--quiet"};
  const pid_t mapper = test::spawnProcess(args);
  ASSERT_GT(mapper, 0);
  std::this_thread::sleep_for(std::chrono::milliseconds(800));

  lcm::LCM lcm(kUrl);
  ASSERT_TRUE(lcm.good());
  Replies replies;
  lcm.subscribe("CBLOX_CMD_REPLY", &Replies::onReply, &replies);
  CovarianceResponder responder;
  responder.lcm = &lcm;
  lcm.subscribe("CBLOX_COV_REQUEST", &CovarianceResponder::onRequest, &responder);

  // The simulated room at 160 x 120, played as capture + tracker would.
  SourceConfig options;
  options.trajectory = "orbit";
  options.max_frames = 30;
  options.sim.renderer.rig.stereo = PinholeIntrinsics{160.0, 160.0, 79.5, 59.5, 160, 120};
  std::string error;
  auto source = openFrameSource("sim:room", options, &error);
  ASSERT_NE(source, nullptr) << error;
  CaptureFrame frame;
  int frames = 0;
  const int64_t t0 = 1'700'000'000'000'000;
  while (source->next(&frame, &error) == FrameSource::Status::kFrame) {
    const int64_t utime = t0 + frame.timestamp_ns / 1000;
    const depth_frame_t depth =
        toDepthFrameMsg(frame, source->info(), utime, DepthEncoding::kFloat32Metres);
    frame_pose_t pose{};
    pose.utime = utime;
    pose.frame_id = frame.frame_id;
    pose.T_G_C = toPoseMsg(*frame.T_G_C);
    pose.tracking_state = frame_pose_t::OK;
    pose.tracking_jump = false;
    pose.map_epoch = 0;
    // Tracked against the newest keyframe (every 5th frame is one): never a revisit.
    pose.reference_keyframe_id = frame.frame_id - frame.frame_id % 5;
    lcm.publish("CBLOX_FRAME_POSE", &pose);
    if (frame.frame_id % 5 == 0) {
      keyframe_t keyframe{};
      keyframe.utime = utime;
      keyframe.keyframe_id = frame.frame_id;
      keyframe.frame_id = frame.frame_id;
      keyframe.T_G_K = toPoseMsg(*frame.T_G_C);
      // Keyframe k sees landmarks [10 k, 10 k + 100): subvolumes 0 ([0, 150)) and 1
      // ([100, 250)) share 50, a third of each.
      for (int64_t l = 10 * frame.frame_id; l < 10 * frame.frame_id + 100; ++l) {
        keyframe.landmark_ids.push_back(l);
      }
      keyframe.num_landmarks = static_cast<int32_t>(keyframe.landmark_ids.size());
      lcm.publish("CBLOX_KEYFRAME", &keyframe);
    }
    lcm.publish("CBLOX_DEPTH", &depth);
    ++frames;
    lcm.handleTimeout(50);  // ~20 Hz
  }
  ASSERT_EQ(frames, 30);

  // Malformed input: bytes that are no message, and a depth image whose data is short.
  const uint8_t garbage[5] = {1, 2, 3, 4, 5};
  lcm.publish("CBLOX_DEPTH", garbage, sizeof(garbage));
  depth_frame_t truncated =
      toDepthFrameMsg(frame, source->info(), t0 + 10'000'000, DepthEncoding::kFloat32Metres);
  truncated.depth.data.resize(100);
  truncated.depth.size = 100;
  lcm.publish("CBLOX_DEPTH", &truncated);
  frame_pose_t nan_pose{};
  nan_pose.utime = t0 + 20'000'000;
  nan_pose.frame_id = 999;
  nan_pose.T_G_C = toPoseMsg(Transformationd::Identity());
  nan_pose.T_G_C.position[0] = std::nan("");
  nan_pose.tracking_state = frame_pose_t::OK;
  nan_pose.tracking_jump = false;
  nan_pose.map_epoch = 0;
  nan_pose.reference_keyframe_id = -1;
  lcm.publish("CBLOX_FRAME_POSE", &nan_pose);

  // A loop correction moves keyframe 0 (the subvolume's anchor) and names an unknown one.
  keyframe_pose_batch_t batch{};
  batch.utime = t0 + 30'000'000;
  batch.reason = keyframe_pose_batch_t::LOOP_CORRECTION;
  batch.keyframe_ids = {0, 424242};
  batch.poses = {
      toPoseMsg(Transformationd(Eigen::Quaterniond::Identity(), Eigen::Vector3d(1.0, 0.0, 0.0))),
      toPoseMsg(Transformationd::Identity())};
  batch.num_keyframes = 2;
  lcm.publish("CBLOX_KEYFRAME_POSES", &batch);
  std::this_thread::sleep_for(std::chrono::milliseconds(800));

  const auto status = statusOf(&lcm, &replies, 77);
  ASSERT_FALSE(status.empty()) << "no status reply";
  EXPECT_EQ(status.at("pose_source"), "tracker");
  EXPECT_GE(value(status, "frames_integrated"), 25);
  EXPECT_GE(value(status, "keyframes"), 6);
  EXPECT_EQ(value(status, "pose_batches"), 1);
  // Both the bytes and the image whose data disagrees with its size fail to decode.
  EXPECT_EQ(value(status, "rejected_depth_undecodable"), 2);
  EXPECT_EQ(value(status, "rejected_pose_invalid"), 1);
  EXPECT_EQ(value(status, "rejected_keyframe_pose_unknown"), 1);
  // Map maintenance: subvolume 1 (anchor keyframe 10) given subvolume 0 (keyframe 0) was
  // asked for once subvolume 2 took over, answered certain, and fused.
  ASSERT_EQ(responder.requests.size(), 1u);
  ASSERT_EQ(responder.requests[0].num_pairs, 1);
  EXPECT_EQ(responder.requests[0].keyframe_i[0], 10);
  EXPECT_EQ(responder.requests[0].keyframe_j[0], 0);
  EXPECT_EQ(value(status, "fusion_candidates"), 1);
  EXPECT_EQ(value(status, "covariance_requested"), 1);
  EXPECT_EQ(value(status, "subvolumes_fused"), 1);
  EXPECT_EQ(value(status, "rejected_by_q"), 0);
  EXPECT_EQ(value(status, "subvolumes"), 2);

  // Still alive after all that: a second status answers; SIGTERM ends it cleanly.
  EXPECT_FALSE(statusOf(&lcm, &replies, 78).empty());
  kill(mapper, SIGTERM);
  int exit_status = 0;
  ASSERT_EQ(waitpid(mapper, &exit_status, 0), mapper);
  ASSERT_TRUE(WIFEXITED(exit_status));
  EXPECT_EQ(WEXITSTATUS(exit_status), 0);
}

}  // namespace
}  // namespace cblox
