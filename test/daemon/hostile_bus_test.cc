// The bus is hostile: cblox-mapper (tracker mode), cblox-tracker and cblox-viewer are sent
// valid messages of
// every channel they read, then copies of them with a few bytes changed after the 8-byte
// fingerprint (array and string lengths set to -1, 0x7fffffff, 0x80000000, 0; payloads cut
// short; another type's bytes; random flips). Before the message guard a corrupt length
// ended both processes (std::length_error from the generated decode) and lost the map.
// All must keep running, count what they refused, and still answer afterwards.
// Runs in a private network namespace (scripts/netns-run.sh; ctest does this).

#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <cstdint>
#include <cstring>
#include <map>
#include <optional>
#include <random>
#include <string>
#include <thread>
#include <vector>

#include <cblox/command_reply_t.hpp>
#include <cblox/command_t.hpp>
#include <cblox/covariance_reply_t.hpp>
#include <cblox/distance_request_t.hpp>
#include <cblox/covariance_request_t.hpp>
#include <cblox/heartbeat_t.hpp>
#include <cblox/mesh_update_t.hpp>
#include <gtest/gtest.h>
#include <lcm/lcm-cpp.hpp>

#include "daemon/common/lcm_messages.h"
#include "drivers/open_frame_source.h"
#include "test/test_support/lcm_samples.h"
#include "test/test_support/spawn.h"
#include "test/test_support/temp_dir.h"

namespace cblox {
namespace {

const char* kUrl = "udpm://239.255.76.67:7667?ttl=0&recv_buf_size=4194304";
using Bytes = std::vector<uint8_t>;

template <typename Msg>
Bytes encode(const Msg& msg) {
  Bytes bytes(static_cast<size_t>(msg.getEncodedSize()));
  msg.encode(bytes.data(), 0, static_cast<int>(bytes.size()));
  return bytes;
}

/// The corrupted copies of one valid encoding.
std::vector<Bytes> mutations(const Bytes& valid, std::mt19937* rng) {
  std::vector<Bytes> out;
  const uint32_t values[] = {0xFFFFFFFFu, 0x7FFFFFFFu, 0x80000000u, 0u};
  // Every 4-byte window of a small message, or 48 spread over a large one.
  const size_t n = valid.size();
  const size_t step = n <= 200 ? 1 : (n - 12) / 48;
  for (size_t k = 8; k + 4 <= n; k += step) {
    for (const uint32_t v : values) {
      Bytes b = valid;
      std::memcpy(&b[k], &v, 4);
      out.push_back(std::move(b));
    }
  }
  for (const size_t cut : {size_t{0}, size_t{4}, size_t{8}, n / 2, n - 1}) {
    if (cut < n) out.emplace_back(valid.begin(), valid.begin() + static_cast<long>(cut));
  }
  Bytes longer = valid;
  longer.push_back(0x42);
  out.push_back(std::move(longer));
  for (int i = 0; i < 16; ++i) {
    Bytes b = valid;
    for (int f = 0; f < 4; ++f) b[8 + (*rng)() % (n - 8)] ^= static_cast<uint8_t>(1 + (*rng)() % 255);
    out.push_back(std::move(b));
  }
  return out;
}

struct Listener {
  std::map<std::string, heartbeat_t> heartbeats;  // newest per process, sent after `since`
  int64_t since = 0;
  std::optional<command_reply_t> reply;
  int64_t wanted_reply = 0;
  void onHeartbeat(const lcm::ReceiveBuffer*, const std::string&, const heartbeat_t* m) {
    if (m->utime >= since) heartbeats[m->process] = *m;
  }
  void onReply(const lcm::ReceiveBuffer*, const std::string&, const command_reply_t* m) {
    if (m->command_id == wanted_reply) reply = *m;
  }
};

int64_t counter(const heartbeat_t& hb, const std::string& name) {
  for (int i = 0; i < hb.num_counters; ++i) {
    if (hb.counter_names[i] == name) return hb.counter_values[i];
  }
  ADD_FAILURE() << hb.process << " has no counter " << name;
  return -1;
}

bool alive(pid_t pid) {
  int status = 0;
  return ::waitpid(pid, &status, WNOHANG) == 0;
}

TEST(HostileBusTest, MapperTrackerAndViewerSurviveMutatedMessagesOnEveryChannel) {
  test::TempDir dir("cblox_hostile_bus");
  const pid_t mapper = test::spawnProcess({CBLOX_MAPPER_EXE, "--pose-source", "tracker",
                                           "--output-dir", dir.path().string(), "--lcm-url",
                                           kUrl, "--quiet"});
  const pid_t tracker = test::spawnProcess({CBLOX_TRACKER_EXE, "--vocabulary", "none",
                                            "--initial-pose-from-gt", "--lcm-url", kUrl,
                                            "--quiet"});
  const pid_t viewer = test::spawnProcess({CBLOX_VIEWER_EXE, "--lcm-url", kUrl, "--quiet"});
  ASSERT_GT(mapper, 0);
  ASSERT_GT(tracker, 0);
  ASSERT_GT(viewer, 0);
  // On a failed assertion the processes must not outlive the test.
  struct KillOnExit {
    std::vector<pid_t> pids;
    ~KillOnExit() {
      for (const pid_t pid : pids) {
        if (::kill(pid, SIGKILL) == 0) ::waitpid(pid, nullptr, 0);
      }
    }
  } kill_on_exit{{mapper, tracker, viewer}};
  std::this_thread::sleep_for(std::chrono::milliseconds(1000));

  lcm::LCM lcm(kUrl);
  ASSERT_TRUE(lcm.good());
  Listener listener;
  lcm.subscribe("CBLOX_HEARTBEAT", &Listener::onHeartbeat, &listener);
  lcm.subscribe("CBLOX_CMD_REPLY", &Listener::onReply, &listener);

  // One valid message of every channel the two processes read, from the simulated room.
  SourceConfig options;
  options.max_frames = 1;
  options.sim.renderer.rig.stereo = PinholeIntrinsics{40.0, 40.0, 19.5, 14.5, 40, 30};
  std::string error;
  auto source = openFrameSource("sim:room", options, &error);
  ASSERT_NE(source, nullptr) << error;
  CaptureFrame frame;
  ASSERT_EQ(source->next(&frame, &error), FrameSource::Status::kFrame) << error;
  const int64_t utime = 1'700'000'000'000'000;
  std::map<std::string, Bytes> valid;
  valid["CBLOX_STEREO"] = encode(toStereoPairMsg(frame, source->info(), utime));
  valid["CBLOX_DEPTH"] =
      encode(toDepthFrameMsg(frame, source->info(), utime, DepthEncoding::kUint16Millimetres));
  valid["CBLOX_GT_POSE"] = encode(toGroundTruthMsg(frame, utime));
  valid["CBLOX_FRAME_POSE"] =
      encode(toFramePoseMsg(utime, 0, *frame.T_G_C, frame_pose_t::OK, false, 0));
  valid["CBLOX_KEYFRAME"] = encode(toKeyframeMsg(utime, 0, 0, *frame.T_G_C, {1, 2, 3}, 0));
  valid["CBLOX_KEYFRAME_POSES"] = encode(toKeyframePoseBatchMsg(
      utime, keyframe_pose_batch_t::LOCAL_BA, {{int64_t{0}, *frame.T_G_C}}, 0));
  covariance_request_t request{};
  request.request_id = 1;
  request.num_pairs = 1;
  request.keyframe_i = {1};
  request.keyframe_j = {0};
  valid["CBLOX_COV_REQUEST"] = encode(request);
  covariance_reply_t reply{};
  reply.request_id = 1;
  reply.num_pairs = 1;
  reply.pairs.resize(1);
  reply.pairs[0].error = "none";
  valid["CBLOX_COV_REPLY"] = encode(reply);
  command_t command{};
  command.command_id = 7;
  command.sender = "test";
  command.name = "status";
  command.num_args = 1;
  command.arg_keys = {"k"};
  command.arg_values = {"v"};
  valid["CBLOX_CMD"] = encode(command);
  distance_request_t distance{};
  distance.request_id = 3;
  distance.num_points = 2;
  distance.points = {{0.5, 0.5, 0.5}, {1.0, 0.0, 1.0}};
  valid["CBLOX_DISTANCE_REQUEST"] = encode(distance);
  // The viewer's own channels.
  valid["CBLOX_MESH_UPDATE"] = encode(test::MakeMeshUpdate());
  valid["CBLOX_SUBVOLUMES"] = encode(test::MakeSubvolumeList());
  valid["CBLOX_MAP_STATUS"] = encode(test::MakeMapStatus());
  valid["CBLOX_LOCAL_GRID"] = encode(test::MakeLocalGrid());

  std::mt19937 rng(5);
  size_t sent = 0;
  for (const auto& [channel, bytes] : valid) {
    lcm.publish(channel, bytes.data(), static_cast<unsigned>(bytes.size()));
    for (const auto& [other, other_bytes] : valid) {  // another type on this channel
      if (other != channel) lcm.publish(channel, other_bytes.data(),
                                        static_cast<unsigned>(other_bytes.size()));
    }
    for (const Bytes& bad : mutations(bytes, &rng)) {
      lcm.publish(channel, bad.data(), static_cast<unsigned>(bad.size()));
      if (++sent % 20 == 0) std::this_thread::sleep_for(std::chrono::milliseconds(2));
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(50));
    ASSERT_TRUE(alive(mapper)) << "cblox-mapper died on mutated " << channel << " messages";
    ASSERT_TRUE(alive(tracker)) << "cblox-tracker died on mutated " << channel << " messages";
    ASSERT_TRUE(alive(viewer)) << "cblox-viewer died on mutated " << channel << " messages";
  }
  // Well-formed on the wire, wrong inside: a triangle naming a vertex the block lacks.
  mesh_update_t broken = test::MakeMeshUpdate();
  broken.blocks[0].triangle[0][2] = 3;
  lcm.publish("CBLOX_MESH_UPDATE", &broken);
  std::printf("sent %zu mutated messages over %zu channels\n", sent, valid.size());

  // Both still serve: the mapper answers a command, both send heartbeats that count refusals.
  // Heartbeats sent during the barrage wait in this test's socket: take only later ones.
  listener.heartbeats.clear();
  listener.since = std::chrono::duration_cast<std::chrono::microseconds>(
                       std::chrono::system_clock::now().time_since_epoch())
                       .count();
  listener.wanted_reply = 99;
  command.command_id = 99;
  command.num_args = 0;
  command.arg_keys.clear();
  command.arg_values.clear();
  // UDP: while the mapper still drains the barrage a command datagram may be dropped with a
  // full socket buffer, as on any LCM bus; it is sent again each second until answered.
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(20);
  auto next_send = std::chrono::steady_clock::now();
  while (std::chrono::steady_clock::now() < deadline &&
         (!listener.reply || listener.heartbeats.size() < 3)) {
    if (!listener.reply && std::chrono::steady_clock::now() >= next_send) {
      lcm.publish("CBLOX_CMD", &command);
      next_send += std::chrono::seconds(1);
    }
    lcm.handleTimeout(50);
  }
  ASSERT_TRUE(listener.reply.has_value()) << "the mapper no longer answers commands";
  EXPECT_TRUE(listener.reply->ok);
  ASSERT_EQ(listener.heartbeats.count("cblox-mapper"), 1u);
  ASSERT_EQ(listener.heartbeats.count("cblox-tracker"), 1u);
  ASSERT_EQ(listener.heartbeats.count("cblox-viewer"), 1u);
  const heartbeat_t& v = listener.heartbeats["cblox-viewer"];
  EXPECT_GT(counter(v, "messages_refused_length_out_of_bounds"), 0);
  EXPECT_GT(counter(v, "messages_refused_fingerprint_mismatch"), 0);
  EXPECT_GT(counter(v, "mesh_updates_refused"), 0);
  const heartbeat_t& m = listener.heartbeats["cblox-mapper"];
  const heartbeat_t& t = listener.heartbeats["cblox-tracker"];
  EXPECT_GT(counter(m, "messages_refused_length_out_of_bounds"), 0);
  EXPECT_GT(counter(m, "messages_refused_fingerprint_mismatch"), 0);
  EXPECT_GT(counter(m, "rejected_depth_undecodable"), 0);
  EXPECT_GT(counter(m, "rejected_command_invalid"), 0);
  EXPECT_GT(counter(m, "rejected_distance_request_invalid"), 0);
  EXPECT_GT(counter(t, "messages_refused_length_out_of_bounds"), 0);
  EXPECT_GT(counter(t, "messages_refused_truncated"), 0);
  EXPECT_GT(counter(t, "frames_rejected"), 0);

  ASSERT_EQ(::kill(mapper, SIGTERM), 0);
  ASSERT_EQ(::kill(tracker, SIGTERM), 0);
  ASSERT_EQ(::kill(viewer, SIGTERM), 0);
  kill_on_exit.pids.clear();  // reaped here
  for (const pid_t pid : {mapper, tracker, viewer}) {
    int status = 0;
    ASSERT_EQ(::waitpid(pid, &status, 0), pid);
    EXPECT_TRUE(WIFEXITED(status));
    EXPECT_EQ(WEXITSTATUS(status), 0);
  }
}

}  // namespace
}  // namespace cblox
