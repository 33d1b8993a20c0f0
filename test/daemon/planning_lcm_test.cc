// Multi-process test of the planner interface: cblox-capture plays the simulated room,
// cblox-mapper (planning on, the carving integrator) maps it with ground-truth poses, and
// this test asks distances over LCM (distance_request_t: valid, hostile, too many points,
// another epoch), listens to CBLOX_LOCAL_GRID, and runs cblox-ctl distance / grid /
// esdf-slice. Must run inside a private network namespace (scripts/netns-run.sh).


#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <limits>
#include <map>
#include <optional>
#include <string>
#include <vector>

#include <cblox/distance_reply_t.hpp>
#include <cblox/distance_request_t.hpp>
#include <cblox/heartbeat_t.hpp>
#include <cblox/local_grid_t.hpp>
#include <cblox/map_status_t.hpp>
#include <gtest/gtest.h>
#include <lcm/lcm-cpp.hpp>
#include <opencv2/imgcodecs.hpp>

#include "daemon/common/local_grid_codec.h"
#include "test/test_support/lcm_samples.h"
#include "test/test_support/spawn.h"
#include "test/test_support/temp_dir.h"

namespace cblox {
namespace {

using Clock = std::chrono::steady_clock;
using test::runTool;

const char* kUrl = "udpm://239.255.76.67:7667?ttl=0&recv_buf_size=4194304";
constexpr int kFrames = 40;

struct Bus {
  std::optional<map_status_t> status;
  std::map<int64_t, distance_reply_t> replies;
  std::vector<local_grid_t> grids;
  std::optional<heartbeat_t> mapper_heartbeat;
  void onStatus(const lcm::ReceiveBuffer*, const std::string&, const map_status_t* m) {
    status = *m;
  }
  void onReply(const lcm::ReceiveBuffer*, const std::string&, const distance_reply_t* m) {
    replies[m->request_id] = *m;
  }
  void onGrid(const lcm::ReceiveBuffer*, const std::string&, const local_grid_t* m) {
    grids.push_back(*m);
  }
  void onHeartbeat(const lcm::ReceiveBuffer*, const std::string&, const heartbeat_t* m) {
    if (m->process == "cblox-mapper") mapper_heartbeat = *m;
  }
};

int64_t counter(const heartbeat_t& hb, const std::string& name) {
  for (size_t i = 0; i < hb.counter_names.size() && i < hb.counter_values.size(); ++i) {
    if (hb.counter_names[i] == name) return hb.counter_values[i];
  }
  return -1;
}

distance_request_t request(int64_t id, int64_t epoch, std::vector<std::vector<double>> p) {
  return test::MakeDistanceRequest(id, epoch, std::move(p));
}

/// Publishes `m` and handles LCM until its reply arrives (10 s at most).
std::optional<distance_reply_t> ask(lcm::LCM* lcm, Bus* bus, const distance_request_t& m) {
  lcm->publish("CBLOX_DISTANCE_REQUEST", &m);
  const auto deadline = Clock::now() + std::chrono::seconds(10);
  while (Clock::now() < deadline && bus->replies.count(m.request_id) == 0) lcm->handleTimeout(20);
  const auto it = bus->replies.find(m.request_id);
  if (it == bus->replies.end()) return std::nullopt;
  return it->second;
}

/// Runs cblox-ctl with `args`; its exit status, its output in *output.
int ctl(lcm::LCM* lcm, const test::TempDir& dir, std::vector<std::string> args,
        std::string* output) {
  const std::string log = dir.file("ctl.txt");
  std::string line = std::string(CBLOX_CTL_EXE) + " --lcm-url '" + kUrl + "' --timeout 30";
  for (const std::string& a : args) line += " '" + a + "'";
  const int status = runTool(lcm, {"/bin/sh", "-c", line + " > " + log + " 2>&1"},
                             std::chrono::seconds(60));
  *output = test::readFile(log);
  return status;
}

TEST(PlanningLcmTest, PlannersAskTheMapperOverLcm) {
  test::TempDir dir("planning_lcm");
  const std::string out = dir.file("out");
  const std::string config = dir.write(
      "mapper.yaml",
      "integrator: {type: fast}\n"
      "subvolumes: {keyframe_every_n_frames: 5, max_keyframes_per_subvolume: 4}\n"
      "planning: {enabled: true, refresh_period_s: 0.2, local_grid_period_s: 0.2,\n"
      "           local_grid_size_m: [4.0, 4.0, 2.0], local_grid_resolution_m: 0.1}\n");
  lcm::LCM lcm(kUrl);
  ASSERT_TRUE(lcm.good());
  Bus bus;
  lcm.subscribe("CBLOX_MAP_STATUS", &Bus::onStatus, &bus);
  lcm.subscribe("CBLOX_DISTANCE_REPLY", &Bus::onReply, &bus);
  lcm.subscribe("CBLOX_LOCAL_GRID", &Bus::onGrid, &bus);
  lcm.subscribe("CBLOX_HEARTBEAT", &Bus::onHeartbeat, &bus);
  const pid_t mapper = test::spawnProcess({CBLOX_MAPPER_EXE, "--config", config, "--output-dir",
                                           out, "--pose-source", "ground_truth", "--lcm-url",
                                           kUrl, "--quiet"});
  ASSERT_GT(mapper, 0);
  const auto up = Clock::now();
  while (!bus.status && Clock::now() - up < std::chrono::seconds(10)) lcm.handleTimeout(50);
  ASSERT_TRUE(bus.status.has_value()) << "no CBLOX_MAP_STATUS within 10 s";

  // Before any frame: every point is unknown, and that is an answer.
  const std::optional<distance_reply_t> empty =
      ask(&lcm, &bus, request(1, 0, {{2.5, 3.4, 1.0}}));
  ASSERT_TRUE(empty.has_value());
  EXPECT_EQ(empty->status, distance_reply_t::STATUS_OK);
  ASSERT_EQ(empty->num_points, 1);
  EXPECT_EQ(empty->state[0], distance_reply_t::UNKNOWN);
  EXPECT_TRUE(std::isnan(empty->distance[0]));
  const int64_t epoch = empty->map_epoch;
  EXPECT_GT(epoch, 0);

  ASSERT_EQ(runTool(&lcm,
                    {CBLOX_CAPTURE_EXE, "--source", "sim:room", "--trajectory", "orbit",
                     "--frames", std::to_string(kFrames), "--rate", "10", "--lcm-url", kUrl,
                     "--quiet"},
                    std::chrono::seconds(60)),
            0);
  const auto settle = Clock::now();
  while ((!bus.status || bus.status->frames_integrated + bus.status->frames_dropped +
                                 bus.status->frames_rejected <
                             kFrames) &&
         Clock::now() - settle < std::chrono::seconds(10)) {
    lcm.handleTimeout(50);
  }
  // The slice and the grid make the fields follow the map first (the active subvolume too).
  std::string output;
  ASSERT_EQ(ctl(&lcm, dir, {"esdf-slice", "--z", "1.0", "--out", "slice.png"}, &output), 0)
      << output;
  const cv::Mat slice = cv::imread(out + "/slice.png", cv::IMREAD_COLOR);
  ASSERT_FALSE(slice.empty()) << output;
  EXPECT_GT(slice.cols, 100);
  ASSERT_EQ(ctl(&lcm, dir, {"grid", "--box", "1.5,2.4,0.5,3.5,4.4,1.5", "--resolution", "0.1", "--out",
                            "grid.ply"},
                &output),
            0)
      << output;
  EXPECT_NE(output.find("cells: 4000"), std::string::npos) << output;  // 20 x 20 x 10
  EXPECT_TRUE(std::filesystem::exists(out + "/grid.ply"));

  // The room spans [0, 5] x [0, 6.5] x [0, 2.7] in G; the orbit at 1.4 m height, 1.4 m around
  // (2.5, 3.4) looks at the walls from inside: the line at 1 m height through the middle of
  // the room, 0.5 m from the walls, is observed free space.
  std::vector<std::vector<double>> line;
  for (int i = 0; i < 4096; ++i) line.push_back({0.5 + 4.0 * i / 4095.0, 3.4, 1.0});
  const std::optional<distance_reply_t> r = ask(&lcm, &bus, request(2, epoch, line));
  ASSERT_TRUE(r.has_value());
  EXPECT_EQ(r->status, distance_reply_t::STATUS_OK) << r->message;
  EXPECT_EQ(r->map_epoch, epoch);
  EXPECT_EQ(r->max_distance_m, 2.0f);
  ASSERT_EQ(r->num_points, 4096);
  size_t free = 0, with_gradient = 0;
  std::vector<double> norms;
  for (int k = 0; k < 4096; ++k) {
    if (r->state[k] != distance_reply_t::FREE) continue;
    ++free;
    EXPECT_GT(r->distance[k], 0.0f);
    EXPECT_LE(r->distance[k], 2.0f);
    const std::vector<float>& g = r->gradient[k];
    if (std::isfinite(g[0])) {
      ++with_gradient;
      norms.push_back(std::sqrt(g[0] * g[0] + g[1] * g[1] + g[2] * g[2]));
    }
  }
  EXPECT_GT(free, 4096u / 2);
  EXPECT_GT(with_gradient, free / 2);
  // About unit length: the median within 20 %. Single ones reach 2 where neighbouring voxels
  // disagree (a TSDF's projective distances next to a surface, the medial axis).
  std::sort(norms.begin(), norms.end());
  ASSERT_FALSE(norms.empty());
  EXPECT_NEAR(norms[norms.size() / 2], 1.0, 0.2);
  EXPECT_LT(norms.back(), 3.0);

  // Hostile points: NaN and infinite are INVALID_POINT, a point 1e6 m away UNKNOWN.
  const double nan = std::numeric_limits<double>::quiet_NaN();
  const double inf = std::numeric_limits<double>::infinity();
  const std::optional<distance_reply_t> hostile =
      ask(&lcm, &bus, request(3, 0, {{nan, 3.4, 1.0}, {2.5, inf, 1.0}, {1e6, 3.4, 1.0}}));
  ASSERT_TRUE(hostile.has_value());
  ASSERT_EQ(hostile->num_points, 3);
  EXPECT_EQ(hostile->state[0], distance_reply_t::INVALID_POINT);
  EXPECT_EQ(hostile->state[1], distance_reply_t::INVALID_POINT);
  EXPECT_EQ(hostile->state[2], distance_reply_t::UNKNOWN);
  // More than MAX_POINTS: refused with a reply, nothing answered.
  line.push_back({2.5, 3.4, 1.0});
  const std::optional<distance_reply_t> too_many = ask(&lcm, &bus, request(4, 0, line));
  ASSERT_TRUE(too_many.has_value());
  EXPECT_EQ(too_many->status, distance_reply_t::STATUS_TOO_MANY_POINTS);
  EXPECT_EQ(too_many->num_points, 0);
  // An epoch the mapper does not hold: answered, and said so.
  const std::optional<distance_reply_t> stale =
      ask(&lcm, &bus, request(5, epoch - 1, {{2.5, 3.4, 1.0}}));
  ASSERT_TRUE(stale.has_value());
  EXPECT_EQ(stale->status, distance_reply_t::STATUS_EPOCH_CHANGED);
  EXPECT_EQ(stale->num_points, 1);

  // The local grid around the newest pose: 40 x 40 x 20 cells, decodable, this map's epoch.
  bus.grids.clear();
  const auto grid_wait = Clock::now();
  while (bus.grids.empty() && Clock::now() - grid_wait < std::chrono::seconds(5)) {
    lcm.handleTimeout(50);
  }
  ASSERT_FALSE(bus.grids.empty()) << "no CBLOX_LOCAL_GRID within 5 s";
  const local_grid_t& msg = bus.grids.back();
  EXPECT_EQ(msg.map_epoch, epoch);
  EXPECT_EQ(msg.encoding, local_grid_t::ENCODING_ZLIB);
  LocalGridSample grid;
  std::string error;
  ASSERT_TRUE(decodeLocalGrid(msg, &grid, &error)) << error;
  EXPECT_EQ(grid.grid.size, Eigen::Vector3i(40, 40, 20));
  size_t grid_free = 0;
  for (const VoxelState s : grid.grid.state) grid_free += s == VoxelState::kFree ? 1 : 0;
  EXPECT_GT(grid_free, 0u);
  std::printf("local grid: %d bytes compressed of %d (%.1f %%), %zu free cells of %zu\n",
              msg.num_bytes, msg.raw_size, 100.0 * msg.num_bytes / msg.raw_size, grid_free,
              grid.grid.state.size());

  // cblox-ctl distance prints the answer.
  ASSERT_EQ(ctl(&lcm, dir, {"distance", "2.5", "3.4", "1", "0.5", "3.4", "1"}, &output), 0)
      << output;
  EXPECT_NE(output.find("(2.500, 3.400, 1.000): free, distance"), std::string::npos) << output;
  EXPECT_EQ(ctl(&lcm, dir, {"distance", "2.5", "3.4"}, &output), 2) << output;

  // The heartbeat counts what was answered and refused.
  test::pumpFor(&lcm, std::chrono::milliseconds(1500));
  ASSERT_TRUE(bus.mapper_heartbeat.has_value());
  EXPECT_GE(counter(*bus.mapper_heartbeat, "distance_requests_answered"), 5);
  EXPECT_GE(counter(*bus.mapper_heartbeat, "distance_requests_refused"), 1);
  EXPECT_GE(counter(*bus.mapper_heartbeat, "rejected_distance_request_invalid"), 1);
  EXPECT_GT(counter(*bus.mapper_heartbeat, "local_grids_published"), 0);

  const std::optional<int> stopped =
      test::terminateWhilePumping(&lcm, mapper, std::chrono::seconds(20));
  ASSERT_TRUE(stopped.has_value()) << "cblox-mapper did not stop within 20 s of SIGTERM";
  EXPECT_EQ(*stopped, 0);
}

}  // namespace
}  // namespace cblox
