// Multi-process test: cblox-capture plays the simulated room over LCM, cblox-mapper
// integrates it with ground-truth poses, cblox-ctl asks for the mesh, and the mesh is checked
// against the scene's exact surface (library evaluation and the cblox-eval tool); the live mesh
// stream (CBLOX_MESH_UPDATE, CBLOX_SUBVOLUMES) applied to a MeshMirror is checked the same
// way, and after a refresh asked with cblox-ctl mesh-refresh.
// Must run inside a private network namespace (scripts/netns-run.sh; ctest does this).

#include <signal.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <cstdio>
#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include <gtest/gtest.h>
#include <cblox/heartbeat_t.hpp>
#include <cblox/map_status_t.hpp>
#include <cblox/mesh_update_t.hpp>
#include <cblox/subvolume_list_t.hpp>
#include <lcm/lcm-cpp.hpp>

#include "core/eval/mesh_accuracy.h"
#include "core/io/ply_io.h"
#include "core/mapping/mesh_mirror.h"
#include "daemon/common/mesh_stream_codec.h"
#include "core/raycast/triangle_mesh_raycaster.h"
#include "drivers/open_frame_source.h"
#include "test/test_support/spawn.h"
#include "test/test_support/temp_dir.h"

namespace cblox {
namespace {

using Clock = std::chrono::steady_clock;

const char* kUrl = "udpm://239.255.76.67:7667?ttl=0&recv_buf_size=4194304";
constexpr double kVoxel = 0.04;  // config/mapper.yaml
constexpr int kFrames = 60;

struct Received {
  std::optional<map_status_t> status;
  size_t status_count = 0;
  std::optional<heartbeat_t> mapper_heartbeat;
  MeshMirror mirror;
  size_t mesh_updates = 0, mesh_gaps = 0, mesh_refresh_starts = 0;
  std::string mesh_error;
  void onMeshUpdate(const lcm::ReceiveBuffer*, const std::string&, const mesh_update_t* m) {
    MeshUpdate update;
    std::string error;
    if (!decodeMeshUpdate(*m, &update, &error)) {
      mesh_error = error;
      return;
    }
    const MeshMirror::Result r = mirror.apply(update);
    if (!r.applied) mesh_error = r.error;
    mesh_gaps += r.gap ? 1 : 0;
    mesh_refresh_starts += update.refresh_start ? 1 : 0;
    ++mesh_updates;
  }
  void onSubvolumes(const lcm::ReceiveBuffer*, const std::string&, const subvolume_list_t* m) {
    SubvolumeList list;
    std::string error;
    if (decodeSubvolumeList(*m, &list, &error)) {
      mirror.applySubvolumes(list);
    } else {
      mesh_error = error;
    }
  }
  void onStatus(const lcm::ReceiveBuffer*, const std::string&, const map_status_t* m) {
    status = *m;
    ++status_count;
  }
  void onHeartbeat(const lcm::ReceiveBuffer*, const std::string&, const heartbeat_t* m) {
    if (m->process == "cblox-mapper") mapper_heartbeat = *m;
  }
};

pid_t spawn(const std::vector<std::string>& args) { return test::spawnProcess(args); }
using test::pumpFor;
using test::runTool;

TEST(MapperLcmTest, CaptureMapperCtlEndToEndOnTheSimulatedRoom) {
  test::TempDir dir("mapper_lcm");
  const std::string out = dir.file("out");
  // Shipped defaults, but a new subvolume every 20 frames so the export fuses three.
  const std::string config = dir.write(
      "mapper.yaml", "subvolumes: {keyframe_every_n_frames: 5, max_keyframes_per_subvolume: 4}\n");

  lcm::LCM lcm(kUrl);
  ASSERT_TRUE(lcm.good());
  Received received;
  lcm.subscribe("CBLOX_MAP_STATUS", &Received::onStatus, &received);
  lcm.subscribe("CBLOX_HEARTBEAT", &Received::onHeartbeat, &received);
  lcm.subscribe("CBLOX_MESH_UPDATE", &Received::onMeshUpdate, &received);
  lcm.subscribe("CBLOX_SUBVOLUMES", &Received::onSubvolumes, &received);

  const pid_t mapper = spawn({CBLOX_MAPPER_EXE, "--config", config, "--output-dir", out,
                              "--pose-source", "ground_truth", "--lcm-url", kUrl});
  ASSERT_GT(mapper, 0);
  // The mapper is up when it publishes its first status.
  const auto start = Clock::now();
  while (!received.status && Clock::now() - start < std::chrono::seconds(10)) {
    lcm.handleTimeout(50);
  }
  ASSERT_TRUE(received.status.has_value()) << "no CBLOX_MAP_STATUS within 10 s";

  const int capture_status =
      runTool(&lcm,
              {CBLOX_CAPTURE_EXE, "--source", "sim:room", "--trajectory", "orbit", "--frames",
               std::to_string(kFrames), "--rate", "10", "--lcm-url", kUrl, "--quiet"},
              std::chrono::seconds(60));
  ASSERT_EQ(capture_status, 0);

  // Wait until the mapper has accounted for every frame (integrated, dropped or rejected).
  const auto settle = Clock::now();
  auto accounted = [&] {
    const map_status_t& s = *received.status;
    return s.frames_integrated + s.frames_dropped + s.frames_rejected;
  };
  while (accounted() < kFrames && Clock::now() - settle < std::chrono::seconds(10)) {
    lcm.handleTimeout(50);
  }
  const map_status_t before_export = *received.status;
  std::printf(
      "mapper status: received %lld, integrated %lld, dropped %lld, rejected %lld, "
      "%d subvolumes, %lld blocks, integration median %.1f ms p99 %.1f ms\n",
      static_cast<long long>(before_export.frames_received),
      static_cast<long long>(before_export.frames_integrated),
      static_cast<long long>(before_export.frames_dropped),
      static_cast<long long>(before_export.frames_rejected), before_export.num_subvolumes,
      static_cast<long long>(before_export.num_blocks), before_export.integration_ms_median,
      before_export.integration_ms_p99);
  EXPECT_EQ(before_export.frames_received, kFrames);
  EXPECT_GT(before_export.frames_integrated, 0);
  EXPECT_GE(before_export.frames_integrated, kFrames * 9 / 10);  // 10 Hz leaves no reason to drop
  EXPECT_EQ(before_export.frames_rejected, 0);
  EXPECT_EQ(before_export.num_subvolumes, 3);
  EXPECT_GT(before_export.num_blocks, 0);

  // The operator asks for the mesh.
  EXPECT_EQ(
      runTool(&lcm,
              {CBLOX_CTL_EXE, "--lcm-url", kUrl, "--timeout", "30", "export-mesh", "room.ply"},
              std::chrono::seconds(40)),
      0);
  const std::string mesh_path = out + "/room.ply";
  ASSERT_TRUE(std::filesystem::exists(mesh_path));
  EXPECT_EQ(runTool(&lcm,
                    {CBLOX_CTL_EXE, "--lcm-url", kUrl, "--timeout", "30", "export-submap-meshes",
                     "subvolumes"},
                    std::chrono::seconds(40)),
            0);
  for (int id = 0; id < 3; ++id) {
    char name[64];
    std::snprintf(name, sizeof(name), "/subvolumes/submap_%04d.ply", id);
    EXPECT_TRUE(std::filesystem::exists(out + name)) << name;
  }
  // Paths outside the output directory are refused (exit 1: the mapper answered "failed").
  EXPECT_EQ(runTool(&lcm, {CBLOX_CTL_EXE, "--lcm-url", kUrl, "export-mesh", "../escape.ply"},
                    std::chrono::seconds(20)),
            1);
  EXPECT_FALSE(std::filesystem::exists(dir.file("escape.ply")));
  EXPECT_EQ(runTool(&lcm, {CBLOX_CTL_EXE, "--lcm-url", kUrl, "status"}, std::chrono::seconds(20)),
            0);

  // Accuracy against the scene's exact surface: the export, and the live stream's mirror once
  // a period has passed since the last frame (nothing pending), before and after a refresh.
  std::string error;
  Mesh mesh;
  ASSERT_TRUE(readPly(mesh_path, &mesh, &error)) << error;
  const std::shared_ptr<const Mesh> scene = loadSimSceneMesh("sim:room", &error);
  ASSERT_NE(scene, nullptr) << error;
  const auto raycaster = TriangleMeshRaycaster::create(*scene, &error);
  ASSERT_NE(raycaster, nullptr) << error;
  MeshAccuracyConfig options;
  options.completeness_threshold_m = 2.0 * kVoxel;
  const auto check = [&](const Mesh& m, const char* what) {
    const std::optional<MeshAccuracy> accuracy =
        evaluateMeshAccuracy(*raycaster, m, options, &error);
    ASSERT_TRUE(accuracy.has_value()) << error;
    const ErrorStatistics& a = accuracy->accuracy_m;
    std::printf(
        "%s: %zu vertices; accuracy median %.2f mm, RMSE %.2f mm, p90 %.2f mm, "
        "max %.2f mm; completeness %.1f %% within %.0f mm\n",
        what, m.numVertices(), a.median * 1e3, a.rmse * 1e3, a.p90 * 1e3, a.max * 1e3,
        100.0 * accuracy->completeness, options.completeness_threshold_m * 1e3);
    EXPECT_GT(m.numVertices(), 1000u) << what;
    EXPECT_LT(a.median, 0.25 * kVoxel) << what;
    EXPECT_LT(a.rmse, kVoxel) << what;
  };
  check(mesh, "mesh");

  pumpFor(&lcm, std::chrono::milliseconds(2500));
  EXPECT_EQ(received.mesh_error, "");
  EXPECT_EQ(received.mesh_gaps, 0u);
  EXPECT_TRUE(received.mirror.complete());
  EXPECT_EQ(received.mesh_refresh_starts, 1u);  // the mapper's first update
  EXPECT_EQ(received.mirror.subvolumes().subvolumes.size(), 3u);
  EXPECT_EQ(received.mirror.blocks().size(), 3u);
  const auto held = received.mirror.blocks();
  check(received.mirror.meshInG(), "live mesh stream");
  EXPECT_EQ(runTool(&lcm, {CBLOX_CTL_EXE, "--lcm-url", kUrl, "mesh-refresh"},
                    std::chrono::seconds(20)),
            0);
  pumpFor(&lcm, std::chrono::milliseconds(2500));
  EXPECT_EQ(received.mesh_refresh_starts, 2u);
  EXPECT_TRUE(received.mirror.complete());
  EXPECT_TRUE(received.mirror.blocks() == held) << "a refresh resent other meshes";

  // The evaluation tool agrees (exit 0, JSON written).
  const std::string gt_path = dir.file("room_gt.ply");
  ASSERT_TRUE(writePly(gt_path, *scene, PlyFormat::kBinaryLittleEndian, &error)) << error;
  EXPECT_EQ(runTool(&lcm,
                    {CBLOX_EVAL_EXE, "--gt-mesh", gt_path, "--mesh", mesh_path, "--threshold",
                     "0.08", "--json", dir.file("eval.json")},
                    std::chrono::seconds(60)),
            0);
  EXPECT_NE(test::readFile(dir.file("eval.json")).find("\"median_m\""), std::string::npos);

  // Graceful stop on SIGTERM: exit 0, a last heartbeat "stopped".
  const std::optional<int> mapper_status =
      test::terminateWhilePumping(&lcm, mapper, std::chrono::seconds(20));
  ASSERT_TRUE(mapper_status.has_value()) << "cblox-mapper did not stop within 20 s of SIGTERM";
  EXPECT_EQ(*mapper_status, 0);
  pumpFor(&lcm, std::chrono::milliseconds(300));
  ASSERT_TRUE(received.mapper_heartbeat.has_value());
  EXPECT_EQ(received.mapper_heartbeat->state, "stopped");
  const heartbeat_t& hb = *received.mapper_heartbeat;
  for (size_t i = 0; i < hb.counter_names.size(); ++i) {
    if (hb.counter_names[i] == "mesh_updates_sent") {
      EXPECT_GE(hb.counter_values[i], static_cast<int64_t>(received.mesh_updates));
    }
    if (hb.counter_names[i] == "mesh_refreshes") {
      EXPECT_EQ(hb.counter_values[i], 2);
    }
  }
  EXPECT_GE(received.status_count, 3u);
}

TEST(MapperLcmTest, BadConfigurationExitsWithStatusTwo) {
  test::TempDir dir("mapper_lcm");
  const std::string config = dir.write("bad.yaml", "layer: {voxel_sise: 0.04}\n");
  for (const std::vector<std::string>& args :
       {std::vector<std::string>{CBLOX_MAPPER_EXE, "--config", config},
        std::vector<std::string>{CBLOX_MAPPER_EXE, "--pose-source", "imu"},
        std::vector<std::string>{CBLOX_MAPPER_EXE, "--config", dir.file("missing.yaml")},
        std::vector<std::string>{CBLOX_MAPPER_EXE, "--bogus", "1"}}) {
    const pid_t pid = spawn(args);
    int status = 0;
    ASSERT_EQ(waitpid(pid, &status, 0), pid);
    ASSERT_TRUE(WIFEXITED(status));
    EXPECT_EQ(WEXITSTATUS(status), 2) << args[1] << " " << args[2];
  }
}

}  // namespace
}  // namespace cblox
