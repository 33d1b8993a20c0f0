// cblox-ctl status --all against heartbeats and a map status this test publishes (with
// malformed messages among them): the rows (pid, rate and CPU share from two heartbeats,
// RSS, input silence, state), "not heard", the map line, and exit status 0 / 4 / 2. And the
// command path ignores malformed replies (decoded through the wire check).
// Must run inside a private network namespace (scripts/netns-run.sh; ctest does this).

#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <cstdio>
#include <map>
#include <sstream>
#include <string>
#include <vector>

#include <gtest/gtest.h>
#include <cblox/command_reply_t.hpp>
#include <cblox/command_t.hpp>
#include <cblox/heartbeat_t.hpp>
#include <cblox/map_status_t.hpp>
#include <lcm/lcm-cpp.hpp>

#include "test/test_support/read_file.h"

namespace {

using Clock = std::chrono::steady_clock;
const char* kUrl = "udpm://239.255.76.67:7667?ttl=0";

int64_t wallUtime() {
  return std::chrono::duration_cast<std::chrono::microseconds>(
             std::chrono::system_clock::now().time_since_epoch())
      .count();
}

cblox::heartbeat_t heartbeat(const std::string& process, int32_t pid, int64_t utime,
                             const std::string& state,
                             const std::vector<std::pair<std::string, int64_t>>& counters) {
  cblox::heartbeat_t hb;
  hb.utime = utime;
  hb.process = process;
  hb.pid = pid;
  hb.state = state;
  for (const auto& [name, value] : counters) {
    hb.counter_names.push_back(name);
    hb.counter_values.push_back(value);
  }
  hb.num_counters = static_cast<int32_t>(hb.counter_names.size());
  return hb;
}

/// Fake processes on the bus: every 250 ms (in their utime) a heartbeat of capture and tracker
/// (counters rising at known rates), one of cblox-replay, a map status and malformed bytes.
struct Bus {
  lcm::LCM lcm{kUrl};
  int64_t base_utime = wallUtime();
  int tick = 0;
  std::string tracker_state = "input silent: CBLOX_STEREO for 5.2 s; tracking";
  bool mapper = false;
  // Command replies: malformed ones first, then (if answer) the right one.
  bool answer = true;
  void onCommand(const lcm::ReceiveBuffer*, const std::string&, const cblox::command_t* cmd) {
    const uint8_t garbage[] = {0xde, 0xad, 0xbe, 0xef, 1, 2, 3, 4, 5, 6, 7, 8, 9};
    lcm.publish("CBLOX_CMD_REPLY", garbage, sizeof(garbage));
    cblox::command_reply_t reply;
    reply.command_id = cmd->command_id;
    reply.ok = true;
    reply.message = "status follows";
    reply.value_keys = {"subvolumes"};
    reply.values = {"3"};
    reply.num_values = 1;
    std::vector<uint8_t> bytes(static_cast<size_t>(reply.getEncodedSize()));
    reply.encode(bytes.data(), 0, static_cast<int>(bytes.size()));
    lcm.publish("CBLOX_CMD_REPLY", bytes.data(), static_cast<unsigned>(bytes.size() - 3));  // cut
    if (answer) lcm.publish("CBLOX_CMD_REPLY", &reply);
  }

  void publishTick() {
    const int64_t utime = base_utime + 250000LL * tick;
    const int64_t k = tick;
    const cblox::heartbeat_t capture = heartbeat("cblox-capture", 1111, utime, "running",
                                                 {{"frames_published", 5 * k},  // 20 frames/s
                                                  {"source_gaps", 0},
                                                  {"input_silent", 0},
                                                  {"input_age_ms", 40},
                                                  {"cpu_ms", 125 * k},  // 50 % of a core
                                                  {"rss_kib", 204800}});
    lcm.publish("CBLOX_HEARTBEAT", &capture);
    const cblox::heartbeat_t tracker = heartbeat("cblox-tracker", 2222, utime, tracker_state,
                                                 {{"frames_processed", 100},
                                                  {"frames_dropped", 3},
                                                  {"input_silent", 1},
                                                  {"input_age_ms", 5200},
                                                  {"cpu_ms", 1000},
                                                  {"rss_kib", 102400}});
    lcm.publish("CBLOX_HEARTBEAT", &tracker);
    if (mapper) {
      const cblox::heartbeat_t m = heartbeat("cblox-mapper", 4444, utime, "running",
                                             {{"frames_integrated", 10 * k},
                                              {"frames_dropped", 0},
                                              {"frames_pending", 2},
                                              {"input_silent", 0},
                                              {"input_age_ms", 10},
                                              {"cpu_ms", 50 * k},
                                              {"rss_kib", 51200}});
      lcm.publish("CBLOX_HEARTBEAT", &m);
    }
    if (tick == 2) {  // once: one heartbeat only
      const cblox::heartbeat_t replay =
          heartbeat("cblox-replay", 3333, utime, "replaying", {{"cpu_ms", 500}});
      lcm.publish("CBLOX_HEARTBEAT", &replay);
    }
    cblox::map_status_t status{};
    status.utime = utime;
    status.num_subvolumes = 3;
    status.active_subvolume_id = 2;
    status.num_blocks = 1234;
    status.memory_bytes = 10 * 1048576;
    status.frames_integrated = 300;
    status.frames_dropped = 2;
    status.frames_rejected = 1;
    status.integration_ms_median = 5.5f;
    status.integration_ms_p99 = 9.0f;
    status.subvolumes_fused = 1;
    status.checkpoint_dir = "/data/ckpt";
    status.checkpoint_generation = 42;
    status.checkpoints_written = 40;
    status.checkpoint_failures = 1;
    status.last_checkpoint_utime = utime - 2'000'000;
    status.last_checkpoint_ms = 12.5f;
    lcm.publish("CBLOX_MAP_STATUS", &status);
    const uint8_t garbage[] = {1, 2, 3, 4, 5, 6, 7, 8, 0x7f, 0xff, 0xff, 0xff, 0};
    lcm.publish("CBLOX_HEARTBEAT", garbage, sizeof(garbage));
    ++tick;
  }
};

/// Runs cblox-ctl with `args` while the bus publishes every 250 ms and commands are answered;
/// returns its exit status, its output in *output.
int runCtl(Bus* bus, const std::vector<std::string>& args, std::string* output) {
  const std::string out_path = "/tmp/cblox_ctl_status_" + std::to_string(::getpid());
  std::string cmd = std::string(CBLOX_CTL_EXE) + " --lcm-url '" + kUrl + "'";
  for (const std::string& a : args) cmd += " '" + a + "'";
  std::vector<std::string> all = {"/bin/sh", "-c", cmd + " > " + out_path + " 2>&1"};
  std::vector<char*> argv;
  for (std::string& a : all) argv.push_back(a.data());
  argv.push_back(nullptr);
  pid_t pid = -1;
  EXPECT_EQ(posix_spawn(&pid, argv[0], nullptr, nullptr, argv.data(), nullptr), 0);
  int status = 0;
  const auto deadline = Clock::now() + std::chrono::seconds(30);
  auto next_tick = Clock::now();
  while (Clock::now() < deadline) {
    if (Clock::now() >= next_tick) {
      bus->publishTick();
      next_tick += std::chrono::milliseconds(250);
    }
    bus->lcm.handleTimeout(20);
    if (waitpid(pid, &status, WNOHANG) == pid) break;
  }
  *output = cblox::test::readFile(out_path);
  std::remove(out_path.c_str());
  return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
}

/// The whitespace-separated words of the output line starting with `name` + " ".
std::vector<std::string> row(const std::string& output, const std::string& name) {
  std::istringstream lines(output);
  std::string line;
  while (std::getline(lines, line)) {
    if (line.rfind(name + " ", 0) != 0) continue;
    std::istringstream words(line);
    std::vector<std::string> out;
    std::string w;
    while (words >> w) out.push_back(w);
    return out;
  }
  return {};
}

bool contains(const std::string& text, const std::string& part) {
  return text.find(part) != std::string::npos;
}

class CtlStatusTest : public testing::Test {
 protected:
  void SetUp() override {
    ASSERT_TRUE(bus_.lcm.good());
    bus_.lcm.subscribe("CBLOX_CMD", &Bus::onCommand, &bus_);
  }
  Bus bus_;
};

TEST_F(CtlStatusTest, OneRowPerProcessAndExitFourWhenAnExpectedOneIsNotHeard) {
  std::string out;
  EXPECT_EQ(runCtl(&bus_, {"status", "--all", "--listen", "1.5"}, &out), 4) << out;
  // name pid last frames/s dropped queue cpu rss input(2 words) state...
  const std::vector<std::string> capture = row(out, "capture");
  ASSERT_GE(capture.size(), 11u) << out;
  EXPECT_EQ(capture[1], "1111");
  EXPECT_EQ(capture[3], "20.0") << out;  // 5 frames per 0.25 s of heartbeat time
  EXPECT_EQ(capture[4], "0");            // source_gaps
  EXPECT_EQ(capture[5], "-");            // no queue counter
  EXPECT_EQ(capture[6], "50%") << out;   // 125 ms CPU per 250 ms
  EXPECT_EQ(capture[7], "200MiB");
  EXPECT_EQ(capture[8], "ok");
  EXPECT_EQ(capture[9], "0.0s");
  EXPECT_EQ(capture[10], "running");

  const std::vector<std::string> tracker = row(out, "tracker");
  ASSERT_GE(tracker.size(), 11u) << out;
  EXPECT_EQ(tracker[1], "2222");
  EXPECT_EQ(tracker[3], "0.0");
  EXPECT_EQ(tracker[4], "3");
  EXPECT_EQ(tracker[6], "0%");
  EXPECT_EQ(tracker[7], "100MiB");
  EXPECT_EQ(tracker[8], "SILENT");
  EXPECT_EQ(tracker[9], "5.2s");
  EXPECT_TRUE(contains(out, "SILENT 5.2s  input silent: CBLOX_STEREO for 5.2 s; tracking")) << out;

  // Another process heard once: no rate, cumulative CPU time.
  const std::vector<std::string> replay = row(out, "replay");
  ASSERT_GE(replay.size(), 10u) << out;
  EXPECT_EQ(replay[1], "3333");
  EXPECT_EQ(replay[3], "-");
  EXPECT_EQ(replay[6], "0.5s");
  EXPECT_EQ(replay[8], "-");

  EXPECT_TRUE(contains(out, "mapper           -  not heard (no heartbeat in 1.5 s)")) << out;
  EXPECT_TRUE(contains(out,
                       "map: 3 subvolumes (active 2), 1234 blocks, 10.0 MiB; frames 300 "
                       "integrated, 2 dropped, 1 rejected; integration median 5.5 ms, p99 9.0 "
                       "ms; 1 fused"))
      << out;
  // The checkpoint line: the generation committed and how long ago (2 s before the status).
  EXPECT_TRUE(contains(out, "\ncheckpoints: /data/ckpt generation 42 (2.")) << out;
  EXPECT_TRUE(contains(out, " s ago, 12.5 ms), 40 written, 1 failed\n")) << out;
  EXPECT_TRUE(contains(out, "malformed messages ignored")) << out;
  EXPECT_TRUE(contains(out, "NOT ALIVE: mapper (expected: capture, tracker, mapper)")) << out;
  // Expected processes first, in order, then the others.
  EXPECT_LT(out.find("\ncapture "), out.find("\ntracker "));
  EXPECT_LT(out.find("\ntracker "), out.find("\nmapper "));
  EXPECT_LT(out.find("\nmapper "), out.find("\nreplay "));
}

TEST_F(CtlStatusTest, ExitZeroWhenEveryExpectedProcessIsAlive) {
  bus_.mapper = true;
  std::string out;
  EXPECT_EQ(runCtl(&bus_, {"status", "--all"}, &out), 0) << out;
  const std::vector<std::string> mapper = row(out, "mapper");
  ASSERT_GE(mapper.size(), 11u) << out;
  EXPECT_EQ(mapper[1], "4444");
  EXPECT_EQ(mapper[3], "40.0");
  EXPECT_EQ(mapper[5], "2");  // frames_pending: the queue
  EXPECT_EQ(mapper[6], "20%");
  EXPECT_TRUE(contains(out, "alive: all expected processes (capture, tracker, mapper)")) << out;

  bus_.mapper = false;
  EXPECT_EQ(runCtl(&bus_, {"status", "--all", "--expect", "capture,cblox-tracker"}, &out), 0)
      << out;
  EXPECT_TRUE(contains(out, "alive: all expected processes (capture, tracker)")) << out;
  EXPECT_EQ(runCtl(&bus_, {"status", "--all", "--expect", ""}, &out), 0) << out;
}

TEST_F(CtlStatusTest, AStoppedProcessIsNotAlive) {
  bus_.tracker_state = "input silent: CBLOX_STEREO for 9.0 s; stopped";
  std::string out;
  EXPECT_EQ(runCtl(&bus_, {"status", "--all", "--expect", "capture,tracker"}, &out), 4) << out;
  EXPECT_TRUE(contains(out, "NOT ALIVE: tracker (expected: capture, tracker)")) << out;
}

TEST_F(CtlStatusTest, UsageErrorsExitTwo) {
  std::string out;
  EXPECT_EQ(runCtl(&bus_, {"status", "--all", "--listen", "0"}, &out), 2) << out;
  EXPECT_EQ(runCtl(&bus_, {"export-mesh", "x.ply", "--all"}, &out), 2) << out;
  EXPECT_EQ(runCtl(&bus_, {"status", "--expect", "mapper"}, &out), 2) << out;
}

TEST_F(CtlStatusTest, CommandRepliesThatFailTheWireCheckAreIgnored) {
  std::string out;
  EXPECT_EQ(runCtl(&bus_, {"status"}, &out), 0) << out;
  EXPECT_TRUE(contains(out, "ok: status follows")) << out;
  EXPECT_TRUE(contains(out, "subvolumes: 3")) << out;
  bus_.answer = false;
  EXPECT_EQ(runCtl(&bus_, {"--timeout", "1", "status"}, &out), 3) << out;
  EXPECT_TRUE(contains(out, "(2 malformed replies ignored)")) << out;
}

}  // namespace
