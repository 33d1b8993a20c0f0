// Multi-process test: cblox-capture publishes the simulator over LCM, this process
// subscribes and checks every message against the same source rendered in-process.
// Must run inside a private network namespace (scripts/netns-run.sh; ctest does this).

#include <signal.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <cstdio>
#include <map>
#include <string>
#include <vector>

#include <cblox/depth_frame_t.hpp>
#include <cblox/heartbeat_t.hpp>
#include <cblox/pose_stamped_t.hpp>
#include <cblox/stereo_pair_t.hpp>
#include <gtest/gtest.h>
#include <lcm/lcm-cpp.hpp>

#include "core/io/ply_io.h"
#include "daemon/common/lcm_messages.h"
#include "drivers/sim/builtin_scenes.h"
#include "drivers/open_frame_source.h"
#include "drivers/stereo_depth/stereo_depth.h"
#include "test/test_support/spawn.h"

namespace cblox {
namespace {

const char* kUrl = "udpm://239.255.76.67:7667?ttl=0&recv_buf_size=4194304";

struct Received {
  std::map<int64_t, stereo_pair_t> stereo;
  std::map<int64_t, depth_frame_t> depth;
  std::map<int64_t, pose_stamped_t> gt;
  std::vector<heartbeat_t> heartbeats;

  void onStereo(const lcm::ReceiveBuffer*, const std::string&, const stereo_pair_t* m) {
    stereo[m->frame_id] = *m;
  }
  void onDepth(const lcm::ReceiveBuffer*, const std::string&, const depth_frame_t* m) {
    depth[m->frame_id] = *m;
  }
  void onGt(const lcm::ReceiveBuffer*, const std::string&, const pose_stamped_t* m) {
    gt[m->frame_id] = *m;
  }
  void onHeartbeat(const lcm::ReceiveBuffer*, const std::string&, const heartbeat_t* m) {
    heartbeats.push_back(*m);
  }
};

pid_t spawn(const std::vector<std::string>& args) { return test::spawnProcess(args); }

// The source the capture process played (`--source sim:room --trajectory orbit --frames N`),
// rendered again in this process.
std::unique_ptr<FrameSource> roomOrbit(int frames) {
  SourceConfig options;
  options.trajectory = "orbit";
  options.max_frames = static_cast<size_t>(frames);
  std::string error;
  std::unique_ptr<FrameSource> source = openFrameSource("sim:room", options, &error);
  EXPECT_NE(source, nullptr) << error;
  return source;
}

// Runs cblox-capture with `args` (and the test's LCM URL), receiving what it publishes until
// it exits; returns its exit status, or -1 (after killing it) when it runs past 60 s.
int runCapture(std::vector<std::string> args, Received* received) {
  lcm::LCM lcm(kUrl);
  if (!lcm.good()) return -2;
  lcm.subscribe("CBLOX_STEREO", &Received::onStereo, received);
  lcm.subscribe("CBLOX_DEPTH", &Received::onDepth, received);
  lcm.subscribe("CBLOX_GT_POSE", &Received::onGt, received);
  lcm.subscribe("CBLOX_HEARTBEAT", &Received::onHeartbeat, received);
  args.insert(args.begin(), CBLOX_CAPTURE_EXE);
  for (const char* extra : {"--lcm-url", kUrl, "--quiet"}) args.emplace_back(extra);
  const pid_t pid = spawn(args);
  if (pid <= 0) return -2;
  int status = 0;
  bool exited = false;
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(60);
  auto drain_until = deadline;
  while (std::chrono::steady_clock::now() < drain_until) {
    lcm.handleTimeout(100);
    if (!exited && waitpid(pid, &status, WNOHANG) == pid) {
      exited = true;
      drain_until = std::chrono::steady_clock::now() + std::chrono::milliseconds(500);
    }
  }
  if (!exited) {
    kill(pid, SIGKILL);
    waitpid(pid, &status, 0);
    return -1;
  }
  return WIFEXITED(status) ? WEXITSTATUS(status) : -3;
}

TEST(CaptureLcmTest, PublishesSimulatorFramesThatMatchTheSourceExactly) {
  constexpr int kFrames = 12;
  Received received;
  ASSERT_EQ(runCapture({"--source", "sim:room", "--trajectory", "orbit", "--frames",
                        std::to_string(kFrames), "--rate", "20", "--depth-encoding", "f32"},
                       &received),
            0);
  ASSERT_EQ(received.stereo.size(), static_cast<size_t>(kFrames));
  ASSERT_EQ(received.depth.size(), static_cast<size_t>(kFrames));
  ASSERT_EQ(received.gt.size(), static_cast<size_t>(kFrames));
  ASSERT_FALSE(received.heartbeats.empty());
  EXPECT_EQ(received.heartbeats.back().process, "cblox-capture");
  EXPECT_EQ(received.heartbeats.back().state, "finished");

  // The same source in this process renders the same frames.
  std::string error;
  const std::unique_ptr<FrameSource> source = roomOrbit(kFrames);
  ASSERT_NE(source, nullptr);
  CaptureFrame frame;
  while (source->next(&frame, &error) == FrameSource::Status::kFrame) {
    const stereo_pair_t& stereo = received.stereo.at(frame.frame_id);
    EXPECT_EQ(stereo.utime, frame.timestamp_ns / 1000);
    GrayImage left, right;
    ASSERT_TRUE(fromImageMsg(stereo.left, &left, &error)) << error;
    ASSERT_TRUE(fromImageMsg(stereo.right, &right, &error)) << error;
    EXPECT_EQ(left.data, frame.left.data);
    EXPECT_EQ(right.data, frame.right.data);
    EXPECT_DOUBLE_EQ(stereo.T_L_R.position[0], source->info().stereo->baseline_m);

    DepthImage depth;
    ASSERT_TRUE(fromDepthImageMsg(received.depth.at(frame.frame_id).depth, &depth, &error));
    EXPECT_EQ(depth.data, frame.depth.data);  // f32: exact
    const auto pose = fromPoseMsg(received.gt.at(frame.frame_id).T_G_C, &error);
    ASSERT_TRUE(pose.has_value()) << error;
    EXPECT_TRUE(pose->isApprox(*frame.T_G_C, 1e-12));
  }
}

// With stereo_depth on, CBLOX_DEPTH carries SGBM depth of the rectified left camera at half
// size instead of the simulator's depth camera: exactly what StereoDepthEstimator computes here
// from the same pairs.
TEST(CaptureLcmTest, PublishesStereoDepthInPlaceOfTheDepthCamera) {
  constexpr int kFrames = 6;
  const std::string config = std::string(CBLOX_CONFIG_DIR) + "/examples/sim_stereo_depth.yaml";
  Received received;
  ASSERT_EQ(runCapture({"--config", config, "--source", "sim:room", "--trajectory", "orbit",
                        "--frames", std::to_string(kFrames), "--rate", "5", "--depth-encoding",
                        "f32"},
                       &received),
            0);
  ASSERT_EQ(received.stereo.size(), static_cast<size_t>(kFrames));
  ASSERT_EQ(received.depth.size(), static_cast<size_t>(kFrames));  // 5 Hz: none superseded
  const heartbeat_t& last = received.heartbeats.back();
  int64_t depth_frames = -1;
  for (int i = 0; i < last.num_counters; ++i) {
    if (last.counter_names[i] == "stereo_depth_frames") depth_frames = last.counter_values[i];
  }
  EXPECT_EQ(depth_frames, kFrames);

  std::string error;
  const std::unique_ptr<FrameSource> source = roomOrbit(kFrames);
  ASSERT_NE(source, nullptr);
  StereoDepthConfig stereo;
  stereo.min_depth_m = 0.4;  // as the example
  auto estimator = StereoDepthEstimator::create(*source->info().stereo, stereo, &error);
  ASSERT_NE(estimator, nullptr) << error;
  CaptureFrame frame;
  while (source->next(&frame, &error) == FrameSource::Status::kFrame) {
    const depth_frame_t& msg = received.depth.at(frame.frame_id);
    EXPECT_EQ(msg.utime, frame.timestamp_ns / 1000);
    EXPECT_EQ(msg.calibration.width, 376);
    EXPECT_EQ(msg.calibration.fx, 229.0);
    EXPECT_FLOAT_EQ(msg.min_depth_m, 0.4f);
    DepthImage depth, expected;
    ASSERT_TRUE(fromDepthImageMsg(msg.depth, &depth, &error)) << error;
    estimator->compute(frame.left, frame.right, &expected);
    EXPECT_EQ(depth.data, expected.data) << frame.frame_id;
  }
}

TEST(CaptureLcmTest, WritesTheSceneMeshAndExits) {
  const std::string path = "/tmp/cblox_capture_scene_" + std::to_string(::getpid()) + ".ply";
  const pid_t pid = spawn({CBLOX_CAPTURE_EXE, "--source", "sim:hall", "--write-scene", path});
  int status = 0;
  ASSERT_EQ(waitpid(pid, &status, 0), pid);
  ASSERT_TRUE(WIFEXITED(status));
  EXPECT_EQ(WEXITSTATUS(status), 0);
  Mesh mesh;
  std::string error;
  ASSERT_TRUE(readPly(path, &mesh, &error)) << error;
  EXPECT_EQ(mesh.numTriangles(), makeIndustrialHall().mesh.numTriangles());
  std::remove(path.c_str());
}

TEST(CaptureLcmTest, BadSourceExitsWithStatusTwo) {
  const pid_t pid = spawn({CBLOX_CAPTURE_EXE, "--source", "euroc:/nonexistent", "--quiet"});
  int status = 0;
  ASSERT_EQ(waitpid(pid, &status, 0), pid);
  ASSERT_TRUE(WIFEXITED(status));
  EXPECT_EQ(WEXITSTATUS(status), 2);
  const pid_t pid2 = spawn({CBLOX_CAPTURE_EXE, "--rate", "fast"});
  ASSERT_EQ(waitpid(pid2, &status, 0), pid2);
  EXPECT_EQ(WEXITSTATUS(status), 2);
}

// A camera that is not there: exit 2 at once, or after --device-wait of retrying (the
// systemd unit waits for cameras still enumerating at boot). No device is faked: the node
// does not exist.
TEST(CaptureLcmTest, MissingCameraExitsWithStatusTwoAfterTheWait) {
  for (const double wait_s : {0.0, 1.5}) {
    const auto start = std::chrono::steady_clock::now();
    const pid_t pid = spawn({CBLOX_CAPTURE_EXE, "--source", "v4l2:/dev/video-cblox-absent",
                             "--device-wait", std::to_string(wait_s), "--lcm-url", kUrl,
                             "--quiet"});
    int status = 0;
    ASSERT_EQ(waitpid(pid, &status, 0), pid);
    const double took =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    ASSERT_TRUE(WIFEXITED(status));
    EXPECT_EQ(WEXITSTATUS(status), 2) << wait_s;
    EXPECT_GE(took, wait_s) << wait_s;
    EXPECT_LT(took, wait_s + 10.0) << wait_s;
  }
}

}  // namespace
}  // namespace cblox
