// The Mapper in-process (no LCM): ground-truth and tracker pose modes, subvolume creation,
// exports confined to the output directory, pose batches, rejected and dropped frames, maps
// saved and loaded over the command channel (save_map, load_map, and --load-map's loadMap).

#include "core/mapping/mapper.h"

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <future>
#include <limits>
#include <map>
#include <memory>
#include <mutex>
#include <optional>
#include <set>
#include <string>
#include <thread>
#include <utility>
#include <vector>

#include <gtest/gtest.h>
#include <sched.h>
#include <sys/resource.h>

#include "core/esdf/esdf_query.h"
#include "core/io/ply_io.h"
#include "core/mapping/map_epoch_key.h"
#include "core/mapping/mesh_mirror.h"
#include "core/mesh/block_mesher.h"
#include "drivers/synthetic/scenes.h"
#include "drivers/synthetic/synthetic_frame_source.h"
#include "test/mapping/room_frames.h"
#include "test/test_support/temp_dir.h"

namespace cblox {
namespace {

using std::chrono::milliseconds;

constexpr float kVoxel = 0.04f;
// How long a test waits for the mapper's threads to fall idle before it calls it a hang:
// with planning on, idle includes the worker's distance fields, which take seconds each
// under ThreadSanitizer on a loaded machine.
constexpr milliseconds kIdleTimeout(60000);

MapperConfig testConfig(const std::filesystem::path& output_dir) {
  MapperConfig config;
  config.layer = LayerConfig{kVoxel, 8};
  config.output_dir = output_dir.string();
  config.keyframe_every_n_frames = 3;
  config.creation.max_keyframes_per_subvolume = 2;  // a new subvolume every 6 frames
  config.worker_sched_idle = false;                 // keep test timing independent of load
  config.worker_niceness = 0;
  // Every frame whole: under ThreadSanitizer on a loaded machine the default 80 ms budget
  // ran out before any block of some frames was integrated.
  config.integrator.max_integration_time_s = 0.0;
  return config;
}

/// Log lines collected from the mapper's threads.
struct LogLines {
  std::mutex mutex;
  std::vector<std::string> lines;
  Mapper::LogSink sink() {
    return [this](const std::string& line) {
      std::lock_guard<std::mutex> lock(mutex);
      lines.push_back(line);
    };
  }
  size_t countContaining(const std::string& text) {
    std::lock_guard<std::mutex> lock(mutex);
    return static_cast<size_t>(std::count_if(lines.begin(), lines.end(), [&](const auto& l) {
      return l.find(text) != std::string::npos;
    }));
  }
};

/// Feeds frames [begin, end) with their ground-truth poses, one at a time (no drops).
void feed(Mapper* mapper, size_t begin, size_t end) {
  const auto& frames = roomFrames();
  for (size_t i = begin; i < end; ++i) {
    ASSERT_TRUE(mapper->onDepthFrame(depthFrame(frames[i], static_cast<int64_t>(i))));
    ASSERT_TRUE(mapper->onFramePose(groundTruthPose(utimeOf(frames[i]), frames[i].T_G_C)));
    ASSERT_TRUE(mapper->waitUntilIdle(kIdleTimeout));
  }
}

/// Applies keyframe `key` at (x, y, 0), unrotated, 0.1 s after the previous one (`utime`).
void keyframeAt(Mapper* mapper, int64_t* utime, int64_t key, double x, double y = 0.0) {
  *utime += 100000;
  const Transformationd T_G_K(Eigen::Quaterniond::Identity(), Eigen::Vector3d(x, y, 0.0));
  ASSERT_TRUE(mapper->onKeyframe(key, *utime, T_G_K));
  ASSERT_TRUE(mapper->waitUntilIdle(kIdleTimeout));
}

MapperReply runCommand(Mapper* mapper, const MapperCommand& command);

MapperReply runCommand(Mapper* mapper, const std::string& name, const std::string& path = "") {
  MapperCommand command;
  command.id = 42;
  command.name = name;
  if (!path.empty()) command.args["path"] = path;
  return runCommand(mapper, command);
}

MapperReply runCommand(Mapper* mapper, const MapperCommand& command) {
  auto promise = std::make_shared<std::promise<MapperReply>>();
  auto future = promise->get_future();
  mapper->onCommand(command, [promise](const MapperReply& r) { promise->set_value(r); });
  if (future.wait_for(std::chrono::seconds(60)) != std::future_status::ready) {
    ADD_FAILURE() << "no reply to '" << command.name << "' within 60 s";
    return MapperReply{};
  }
  return future.get();
}

double median(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  return v.empty() ? 0.0 : v[v.size() / 2];
}

TEST(MapperTest, GroundTruthModeIntegratesAndStartsASubvolumeEveryNKeyframes) {
  test::TempDir dir("mapper");
  LogLines log;
  Mapper mapper(testConfig(dir.path()), log.sink());
  std::string error;
  ASSERT_TRUE(mapper.start(&error)) << error;
  feed(&mapper, 0, 18);
  const MapperStatus s = mapper.status();
  EXPECT_EQ(s.frames_received, 18u);
  EXPECT_EQ(s.frames_integrated, 18u);
  EXPECT_EQ(s.frames_dropped, 0u);
  EXPECT_EQ(s.frames_rejected, 0u);
  EXPECT_EQ(s.keyframes_applied, 6u);  // frames 0, 3, 6, 9, 12, 15
  ASSERT_EQ(s.num_submaps, 3u);        // anchored at frames 0, 6, 12
  EXPECT_EQ(s.active_submap_id, 2);
  EXPECT_GT(s.num_blocks, 0u);
  EXPECT_GT(s.integration_ms_median, 0.0f);
  const std::vector<SubmapPose> poses = mapper.collection().poseSnapshot();
  for (size_t i = 0; i < poses.size(); ++i) {
    EXPECT_EQ(poses[i].anchor_keyframe, static_cast<KeyframeId>(6 * i));
    // The submap frame is the anchor keyframe's (= that frame's) pose.
    EXPECT_TRUE(poses[i].T_G_M.isApprox(roomFrames()[6 * i].T_G_C, 1e-12));
  }
  EXPECT_TRUE(mapper.collection().getSubmap(0)->isFinished());
  EXPECT_EQ(mapper.collection().getSubmap(1)->keyframeIds(), (std::vector<KeyframeId>{6, 9}));
  EXPECT_EQ(log.countContaining("anchored at keyframe"), 3u);
  mapper.stop();
}

TEST(MapperTest, ThePlanningMapAnswersTheRoomsDistancesAndFollowsPoseBatches) {
  test::TempDir dir("mapper");
  MapperConfig config = testConfig(dir.path());
  config.planning.enabled = true;
  Mapper mapper(config);
  std::string error;
  ASSERT_TRUE(mapper.start(&error)) << error;
  feed(&mapper, 0, 24);
  ASSERT_TRUE(mapper.syncPlanningMap(milliseconds(60000)));
  const PlanningMap* planning = mapper.planningMap();
  ASSERT_NE(planning, nullptr);
  const MapperStatus s = mapper.status();
  EXPECT_EQ(s.planning.fields, s.num_submaps);
  // One field block per TSDF block; no band without carving (planning.band_blocks auto).
  EXPECT_EQ(s.planning.blocks, s.num_blocks);
  EXPECT_EQ(s.memory_bytes, mapper.collection().memoryBytes() + planning->memoryBytes());
  EXPECT_GT(s.esdf_ms_median, 0.0f);
  // Nothing changed since: a refresh computes no field again.
  const uint64_t updates_before = planning->stats().updates;
  ASSERT_TRUE(mapper.syncPlanningMap(milliseconds(60000)));
  EXPECT_EQ(planning->stats().updates, updates_before);

  // A grid through the room against its exact signed distance.
  const AnalyticScene room = makeDemoRoom();
  std::vector<Eigen::Vector3d> points;
  for (double x = -2.7; x <= 2.7; x += 0.11) {
    for (double y = -1.8; y <= 1.8; y += 0.13) {
      for (double z = 0.1; z <= 2.9; z += 0.17) points.emplace_back(x, y, z);
    }
  }
  std::vector<DistanceAnswer> answers;
  planning->queryBatch(points, &answers);
  size_t known = 0, unsafe = 0, farther = 0, wrongly_occupied = 0;
  std::vector<double> near_errors;
  for (size_t i = 0; i < points.size(); ++i) {
    const double truth = room.signedDistance(points[i]);
    const DistanceAnswer& a = answers[i];
    if (a.state == VoxelState::kUnknown) {
      EXPECT_TRUE(std::isnan(a.distance));
      continue;
    }
    ++known;
    if (a.state == VoxelState::kOccupied) {
      if (truth > kVoxel) ++wrongly_occupied;
      continue;
    }
    // Free within a voxel of an obstacle, or inside one, and farther than a voxel from it:
    // the unsafe answer. At 4 cm voxels from 24 frames it happens at a few points within a
    // centimetre of a surface seen at grazing angles and at the 5 cm table legs, which the
    // TSDF thins.
    if (truth < kVoxel && a.distance > kVoxel) ++unsafe;
    // Free space whose nearest obstacle was never observed (the back of the pillar, seen
    // from an orbit inside the room) is answered with the nearest observed one: farther.
    if (a.distance > std::min(truth, 2.0) + kVoxel) ++farther;
    // Against the truth as the map lowers its free answers beside obstacles.
    const double lowered =
        lowerBesideSurface(truth, kVoxel, mapper.config().planning.esdf.surface_margin_voxels);
    if (truth < 0.15) near_errors.push_back(std::abs(a.distance - lowered) / kVoxel);
  }
  ASSERT_GT(known, points.size() / 4);
  EXPECT_LE(unsafe, known / 1000) << unsafe << " of " << known;
  EXPECT_LT(farther, known / 20) << farther << " of " << known;
  EXPECT_LT(wrongly_occupied, known / 100) << wrongly_occupied << " of " << known;
  ASSERT_GT(near_errors.size(), 50u);
  // (0.38 voxel without the margin; its taper multiplies the error by 1.5 over a voxel.)
  EXPECT_LT(median(near_errors), 0.6);

  // A pose batch moving every subvolume by the same T: the answers move with them exactly,
  // and no field is computed again.
  const uint64_t updates = planning->stats().updates;
  const Transformationd T(Eigen::Quaterniond(Eigen::AngleAxisd(0.3, Eigen::Vector3d::UnitZ())),
                          Eigen::Vector3d(0.5, -0.2, 0.1));
  std::vector<std::pair<KeyframeId, Transformationd>> batch;
  for (const SubmapPose& pose : mapper.collection().poseSnapshot()) {
    batch.emplace_back(pose.anchor_keyframe, T * pose.T_G_M);
  }
  mapper.onKeyframePoses(batch);
  ASSERT_TRUE(mapper.waitUntilIdle(kIdleTimeout));
  EXPECT_EQ(planning->stats().updates, updates);
  size_t compared = 0;
  for (size_t i = 0; i < points.size(); i += 7) {
    const DistanceAnswer moved = planning->query(T * points[i]);
    ASSERT_EQ(moved.state, answers[i].state) << i;
    if (answers[i].state == VoxelState::kUnknown) continue;
    EXPECT_NEAR(moved.distance, answers[i].distance, 1e-4);
    ++compared;
  }
  EXPECT_GT(compared, 20u);
  mapper.stop();
}

TEST(MapperTest, ExportsAccurateMeshesInsideTheOutputDirectoryOnly) {
  test::TempDir dir("mapper");
  Mapper mapper(testConfig(dir.path()));
  std::string error;
  ASSERT_TRUE(mapper.start(&error)) << error;

  // Nothing integrated yet: the export fails, nothing is written.
  MapperReply empty = runCommand(&mapper, "export_mesh", "empty.ply");
  EXPECT_FALSE(empty.ok);
  EXPECT_FALSE(std::filesystem::exists(dir.file("empty.ply")));

  feed(&mapper, 0, 24);
  const MapperReply reply = runCommand(&mapper, "export_mesh", "meshes/room.ply");
  ASSERT_TRUE(reply.ok) << reply.message;
  EXPECT_EQ(reply.id, 42);
  EXPECT_EQ(reply.value("path"), dir.file("meshes/room.ply"));
  EXPECT_EQ(reply.value("subvolumes"), "4");
  EXPECT_FALSE(reply.value("seconds").empty());
  Mesh mesh;
  ASSERT_TRUE(readPly(dir.file("meshes/room.ply"), &mesh, &error)) << error;
  EXPECT_EQ(std::to_string(mesh.numVertices()), reply.value("vertices"));
  EXPECT_EQ(std::to_string(mesh.numTriangles()), reply.value("triangles"));
  ASSERT_GT(mesh.numVertices(), 1000u);
  // The fused mesh of four subvolumes lies on the analytic room.
  const AnalyticScene room = makeDemoRoom();
  std::vector<double> errors;
  double sum_sq = 0.0;
  for (const Eigen::Vector3f& v : mesh.vertices) {
    errors.push_back(std::abs(room.signedDistance(v.cast<double>())));
    sum_sq += errors.back() * errors.back();
  }
  const double rmse = std::sqrt(sum_sq / static_cast<double>(errors.size()));
  EXPECT_LT(median(errors), 0.25 * kVoxel);
  EXPECT_LT(rmse, kVoxel);

  // An absolute path inside the output directory is fine.
  EXPECT_TRUE(runCommand(&mapper, "export_mesh", dir.file("abs.ply")).ok);
  EXPECT_TRUE(std::filesystem::exists(dir.file("abs.ply")));
  // Escapes are refused at once; nothing is written.
  const std::string escape = dir.path().filename().string() + "_escape.ply";  // unique name
  const std::filesystem::path outside = dir.path().parent_path() / escape;
  for (const std::string& bad : {"../" + escape, "a/../../" + escape, outside.string()}) {
    const MapperReply r = runCommand(&mapper, "export_mesh", bad);
    EXPECT_FALSE(r.ok) << bad;
    EXPECT_FALSE(r.message.empty());
  }
  EXPECT_FALSE(std::filesystem::exists(outside));
  EXPECT_FALSE(runCommand(&mapper, "export_mesh").ok);  // no path
  EXPECT_FALSE(runCommand(&mapper, "make_coffee").ok);
  EXPECT_GE(mapper.status().problem(InputProblem::kCommandInvalid), 5u);

  // One mesh per subvolume, each in its own colour.
  const MapperReply subs = runCommand(&mapper, "export_submap_meshes", "subs");
  ASSERT_TRUE(subs.ok) << subs.message;
  EXPECT_EQ(subs.value("count"), "4");
  std::set<std::tuple<int, int, int>> colours;
  for (int id = 0; id < 4; ++id) {
    Mesh sub;
    char name[32];
    std::snprintf(name, sizeof(name), "subs/submap_%04d.ply", id);
    ASSERT_TRUE(readPly(dir.file(name), &sub, &error)) << error;
    ASSERT_TRUE(sub.hasColors());
    EXPECT_TRUE(std::all_of(sub.colors.begin(), sub.colors.end(),
                            [&](const Color& c) { return c == sub.colors.front(); }));
    EXPECT_EQ(sub.colors.front(), submapColor(id));
    colours.insert({sub.colors.front().r, sub.colors.front().g, sub.colors.front().b});
    // In the global frame: on the room's surfaces.
    std::vector<double> e;
    for (const Eigen::Vector3f& v : sub.vertices) {
      e.push_back(std::abs(room.signedDistance(v.cast<double>())));
    }
    EXPECT_LT(median(e), 0.25 * kVoxel) << name;
  }
  EXPECT_EQ(colours.size(), 4u);

  const MapperReply status = runCommand(&mapper, "status");
  EXPECT_TRUE(status.ok);
  EXPECT_EQ(status.value("frames_integrated"), "24");
  EXPECT_EQ(mapper.status().exports_done, 3u);
  EXPECT_EQ(mapper.status().exports_failed, 1u);
}

TEST(MapperTest, ExportDoesNotStopIntegration) {
  test::TempDir dir("mapper");
  Mapper mapper(testConfig(dir.path()));
  std::string error;
  ASSERT_TRUE(mapper.start(&error)) << error;
  feed(&mapper, 0, 8);
  // Exports run on the worker while frames keep arriving (the active layer is copied under
  // its lock; everything else happens without it).
  std::vector<std::future<MapperReply>> replies;
  std::vector<std::shared_ptr<std::promise<MapperReply>>> promises;
  for (int i = 0; i < 3; ++i) {
    auto promise = std::make_shared<std::promise<MapperReply>>();
    replies.push_back(promise->get_future());
    MapperCommand command;
    command.id = i;
    command.name = i % 2 ? "export_submap_meshes" : "export_mesh";
    command.args["path"] = "concurrent_" + std::to_string(i) + (i % 2 ? "" : ".ply");
    mapper.onCommand(command, [promise](const MapperReply& r) { promise->set_value(r); });
  }
  feed(&mapper, 8, 24);
  for (auto& reply : replies) {
    ASSERT_EQ(reply.wait_for(std::chrono::seconds(60)), std::future_status::ready);
    EXPECT_TRUE(reply.get().ok);
  }
  EXPECT_EQ(mapper.status().frames_integrated, 24u);
}

// Inputs from several threads at once, as in the process (LCM thread, worker replies) plus
// status polling: every frame is accounted for, nothing crashes. Meant for ThreadSanitizer
// (scripts/tsan.sh) as much as for the counters.
TEST(MapperTest, ConcurrentFramesPoseBatchesExportsAndStatus) {
  test::TempDir dir("mapper");
  MapperConfig config = testConfig(dir.path());
  config.max_pose_wait_s = 5.0;
  Mapper mapper(config);
  std::string error;
  ASSERT_TRUE(mapper.start(&error)) << error;
  const auto& frames = roomFrames();
  std::atomic<bool> done{false};
  std::thread feeder([&] {
    for (size_t i = 0; i < frames.size(); ++i) {  // as fast as possible: drops are fine
      mapper.onDepthFrame(depthFrame(frames[i], static_cast<int64_t>(i)));
      mapper.onFramePose(groundTruthPose(utimeOf(frames[i]), frames[i].T_G_C));
      std::this_thread::sleep_for(milliseconds(2));
    }
    done = true;
  });
  std::thread corrector([&] {
    const Transformationd nudge(Eigen::Quaterniond::Identity(), Eigen::Vector3d(0.001, 0, 0));
    while (!done) {
      std::vector<std::pair<KeyframeId, Transformationd>> batch;
      for (KeyframeId k = 0; k < 24; ++k) batch.emplace_back(k, nudge * frames[k].T_G_C);
      mapper.onKeyframePoses(std::move(batch));
      std::this_thread::sleep_for(milliseconds(3));
    }
  });
  std::atomic<int> replies{0}, ok{0};
  std::thread operator_thread([&] {
    for (int i = 0; !done; ++i) {
      MapperCommand command;
      command.id = i;
      command.name = i % 3 == 2 ? "status" : (i % 3 ? "export_submap_meshes" : "export_mesh");
      std::string path = std::to_string(i % 4);  // (not "c" + ...: GCC 12 -Wrestrict)
      if (i % 3 == 0) path += ".ply";
      command.args["path"] = path;
      mapper.onCommand(command, [&](const MapperReply& r) {
        ok += r.ok;
        ++replies;
      });
      (void)mapper.status();
      std::this_thread::sleep_for(milliseconds(5));
    }
  });
  feeder.join();
  corrector.join();
  operator_thread.join();
  ASSERT_TRUE(mapper.waitUntilIdle(milliseconds(30000)));
  mapper.stop();  // answers whatever is still queued
  const MapperStatus s = mapper.status();
  EXPECT_EQ(s.frames_received, frames.size());
  EXPECT_EQ(s.frames_integrated + s.frames_dropped + s.frames_rejected, s.frames_received);
  EXPECT_GT(s.frames_integrated, 0u);
  EXPECT_GT(s.keyframe_batches, 0u);
  EXPECT_GT(replies.load(), 0);
  EXPECT_GT(ok.load(), 0);
}

TEST(MapperTest, KeyframePoseBatchMovesSubvolumesWithoutTouchingVoxels) {
  test::TempDir dir("mapper");
  Mapper mapper(testConfig(dir.path()));
  std::string error;
  ASSERT_TRUE(mapper.start(&error)) << error;
  feed(&mapper, 0, 12);
  ASSERT_EQ(mapper.collection().size(), 2u);
  const size_t blocks = mapper.status().num_blocks;
  const Transformationd moved =
      Transformationd(Eigen::Quaterniond(Eigen::AngleAxisd(0.1, Eigen::Vector3d::UnitZ())),
                      Eigen::Vector3d(1.0, 0.0, 0.0)) *
      roomFrames()[6].T_G_C;
  const double nan = std::numeric_limits<double>::quiet_NaN();
  mapper.onKeyframePoses(
      {{6, moved},
       {999, moved},
       {0, Transformationd(Eigen::Quaterniond::Identity(), Eigen::Vector3d(nan, 0.0, 0.0))}});
  ASSERT_TRUE(mapper.waitUntilIdle(kIdleTimeout));
  EXPECT_TRUE(mapper.collection().getSubmap(1)->T_G_M().isApprox(moved, 1e-12));
  EXPECT_TRUE(mapper.collection().getSubmap(0)->T_G_M().isApprox(roomFrames()[0].T_G_C, 1e-12));
  const MapperStatus s = mapper.status();
  EXPECT_EQ(s.keyframe_batches, 1u);
  EXPECT_EQ(s.submaps_moved, 1u);
  EXPECT_EQ(s.problem(InputProblem::kKeyframePoseUnknown), 1u);
  EXPECT_EQ(s.problem(InputProblem::kKeyframePoseInvalid), 1u);
  EXPECT_EQ(s.num_blocks, blocks);
}

// The mesh stream through a Mapper: a mirror of what its sinks got holds every subvolume's
// block meshes once the frames are integrated and a period passed; a pose batch moves a
// subvolume in the next list without a mesh message; mesh_refresh resends; without sinks
// mesh_refresh is refused.
TEST(MapperTest, TheMeshStreamMirrorsTheMapAndFollowsPoseBatches) {
  test::TempDir dir("mapper");
  MapperConfig config = testConfig(dir.path());
  config.mesh_stream.period_s = 0.05;
  {
    Mapper without(config);
    const MapperReply refused = runCommand(&without, "mesh_refresh");
    EXPECT_FALSE(refused.ok);
    EXPECT_NE(refused.message.find("no mesh stream"), std::string::npos) << refused.message;
  }
  Mapper mapper(config);
  std::mutex mutex;
  MeshMirror mirror;
  size_t updates = 0, refreshes = 0, gaps = 0;
  std::vector<SubvolumeList> lists;
  mapper.setMeshStreamSinks(
      [&](const MeshUpdate& u) {
        std::lock_guard<std::mutex> lock(mutex);
        const MeshMirror::Result r = mirror.apply(u);
        EXPECT_TRUE(r.applied) << r.error;
        gaps += r.gap ? 1 : 0;
        refreshes += u.refresh_start ? 1 : 0;
        ++updates;
      },
      [&](const SubvolumeList& l) {
        std::lock_guard<std::mutex> lock(mutex);
        mirror.applySubvolumes(l);
        lists.push_back(l);
      });
  std::string error;
  ASSERT_TRUE(mapper.start(&error)) << error;
  feed(&mapper, 0, 12);
  const auto settled = [&](size_t lists_before) {
    for (int i = 0; i < 400; ++i) {
      std::this_thread::sleep_for(milliseconds(10));
      std::lock_guard<std::mutex> lock(mutex);
      // Three lists: the third tick began after the second one sent everything it had.
      if (lists.size() >= lists_before + 3 && mirror.complete()) return true;
    }
    return false;
  };
  size_t before = 0;
  {
    std::lock_guard<std::mutex> lock(mutex);
    before = lists.size();
  }
  ASSERT_TRUE(settled(before));

  // Against a full meshing of the layers (the mapper is idle: no frame is being integrated).
  const auto expect_mirror_is_the_map = [&] {
    MeshConfig mesh_config;
    mesh_config.compute_normals = false;
    BlockMesher mesher(mesh_config);
    std::lock_guard<std::mutex> lock(mutex);
    size_t expected_blocks = 0;
    for (const auto& submap : mapper.collection().submaps()) {
      const auto lock_layer = submap->lockLayer();
      for (const auto& [key, block] : submap->layer().blocks()) {
        Mesh mesh;
        mesher.meshBlock(submap->layer(), *block, &mesh);
        if (mesh.empty()) continue;
        ++expected_blocks;
        const auto held = mirror.blocks().find(submap->id());
        ASSERT_NE(held, mirror.blocks().end()) << "subvolume " << submap->id();
        const auto it = held->second.find(key);
        ASSERT_NE(it, held->second.end());
        EXPECT_EQ(it->second.positions.size(), mesh.numVertices());
        EXPECT_EQ(it->second.triangles.size(), mesh.numTriangles());
      }
    }
    EXPECT_EQ(mirror.numBlocks(), expected_blocks);
    EXPECT_GT(expected_blocks, 50u);
  };
  expect_mirror_is_the_map();

  const Transformationd moved =
      Transformationd(Eigen::Quaterniond(Eigen::AngleAxisd(0.1, Eigen::Vector3d::UnitZ())),
                      Eigen::Vector3d(1.0, 0.0, 0.0)) *
      roomFrames()[6].T_G_C;
  size_t updates_before = 0;
  {
    std::lock_guard<std::mutex> lock(mutex);
    before = lists.size();
    updates_before = updates;
  }
  mapper.onKeyframePoses({{6, moved}});
  ASSERT_TRUE(mapper.waitUntilIdle(kIdleTimeout));
  {
    // Lists counted from here: ticks begun before the batch was applied carry the old pose.
    std::lock_guard<std::mutex> lock(mutex);
    before = lists.size();
  }
  ASSERT_TRUE(settled(before));
  {
    std::lock_guard<std::mutex> lock(mutex);
    EXPECT_EQ(updates, updates_before) << "a pose batch resent meshes";
    ASSERT_EQ(lists.back().subvolumes.size(), 2u);
    EXPECT_TRUE(lists.back().subvolumes[1].T_G_S.isApprox(moved, 1e-12));
    before = lists.size();
  }

  const MapperReply refresh = runCommand(&mapper, "mesh_refresh");
  EXPECT_TRUE(refresh.ok) << refresh.message;
  ASSERT_TRUE(settled(before));
  expect_mirror_is_the_map();
  mapper.stop();
  EXPECT_EQ(refreshes, 2u);  // the first period and the one asked for
  EXPECT_EQ(gaps, 0u);
  EXPECT_EQ(mapper.status().mesh_stream.refreshes, 2u);
}

TEST(MapperTest, FrameWithoutPoseIsRejectedAfterTheWait) {
  test::TempDir dir("mapper");
  MapperConfig config = testConfig(dir.path());
  config.max_pose_wait_s = 0.05;
  Mapper mapper(config);
  std::string error;
  ASSERT_TRUE(mapper.start(&error)) << error;
  ASSERT_TRUE(mapper.onDepthFrame(depthFrame(roomFrames()[0], 0)));
  ASSERT_TRUE(mapper.waitUntilIdle(milliseconds(5000)));
  const MapperStatus s = mapper.status();
  EXPECT_EQ(s.problem(InputProblem::kNoPose), 1u);
  EXPECT_EQ(s.frames_rejected, 1u);
  EXPECT_EQ(s.frames_integrated, 0u);
  EXPECT_EQ(s.frames_pending, 0u);
}

// A started mapper with an in-tray of four (in order or newest-wins) that received six frames
// faster than their poses: the in-tray keeps the newest four and drops frames 0 and 1.
std::unique_ptr<Mapper> mapperWithSixFramesWaiting(const test::TempDir& dir, bool in_order) {
  MapperConfig config = testConfig(dir.path());
  config.pending_capacity = 4;
  config.pending_in_order = in_order;
  config.max_pose_wait_s = 30.0;  // nothing expires during the test
  auto mapper = std::make_unique<Mapper>(config);
  std::string error;
  EXPECT_TRUE(mapper->start(&error)) << error;
  for (int i = 0; i < 6; ++i) EXPECT_TRUE(mapper->onDepthFrame(depthFrame(roomFrames()[i], i)));
  EXPECT_EQ(mapper->status().frames_dropped, 2u);
  return mapper;
}

TEST(MapperTest, NewestFrameWinsAndTheOthersAreCountedAsDropped) {
  test::TempDir dir("mapper");
  const std::unique_ptr<Mapper> started = mapperWithSixFramesWaiting(dir, false);
  Mapper& mapper = *started;
  // The newest frame's pose arrives: it is integrated, the three older ones are superseded.
  ASSERT_TRUE(mapper.onFramePose(groundTruthPose(utimeOf(roomFrames()[5]), roomFrames()[5].T_G_C)));
  ASSERT_TRUE(mapper.waitUntilIdle(kIdleTimeout));
  const MapperStatus s = mapper.status();
  EXPECT_EQ(s.frames_received, 6u);
  EXPECT_EQ(s.frames_integrated, 1u);
  EXPECT_EQ(s.frames_dropped, 5u);
  EXPECT_EQ(s.frames_rejected, 0u);
  EXPECT_EQ(mapper.collection().getSubmap(0)->anchorKeyframe(), 5);
}

// The default: waiting frames are integrated in order as their poses come (a tracker that
// caught up after a stall sends them in a burst); only frames pushed out of the full in-tray
// are dropped.
TEST(MapperTest, InOrderEveryWaitingFrameWithAPoseIsIntegrated) {
  test::TempDir dir("mapper");
  ASSERT_TRUE(testConfig(dir.path()).pending_in_order);
  const std::unique_ptr<Mapper> started = mapperWithSixFramesWaiting(dir, true);
  Mapper& mapper = *started;
  for (int i = 2; i < 6; ++i) {
    ASSERT_TRUE(
        mapper.onFramePose(groundTruthPose(utimeOf(roomFrames()[i]), roomFrames()[i].T_G_C)));
  }
  ASSERT_TRUE(mapper.waitUntilIdle(kIdleTimeout));
  const MapperStatus s = mapper.status();
  EXPECT_EQ(s.frames_received, 6u);
  EXPECT_EQ(s.frames_integrated, 4u);
  EXPECT_EQ(s.frames_dropped, 2u);
  EXPECT_EQ(s.frames_rejected, 0u);
}

TEST(MapperTest, BadInputIsRejectedCountedAndLoggedOncePerKind) {
  test::TempDir dir("mapper");
  MapperConfig config = testConfig(dir.path());
  LogLines log;
  Mapper mapper(config, log.sink());
  std::string error;
  ASSERT_TRUE(mapper.start(&error)) << error;
  const SyntheticFrame& f = roomFrames()[2];

  DepthFrame wrong_size = depthFrame(f, 2);
  wrong_size.intrinsics.width = 100;
  EXPECT_FALSE(mapper.onDepthFrame(wrong_size));
  EXPECT_FALSE(mapper.onDepthFrame(wrong_size));  // counted, not logged again
  DepthFrame bad_color = depthFrame(f, 2);
  bad_color.color = ColorImage(10, 10);
  EXPECT_FALSE(mapper.onDepthFrame(bad_color));
  DepthFrame bad_intrinsics = depthFrame(f, 2);
  bad_intrinsics.intrinsics.fx = std::numeric_limits<double>::quiet_NaN();
  EXPECT_FALSE(mapper.onDepthFrame(bad_intrinsics));
  ASSERT_TRUE(mapper.onDepthFrame(depthFrame(f, 2)));
  EXPECT_FALSE(mapper.onDepthFrame(depthFrame(f, 3)));                // same time stamp
  EXPECT_FALSE(mapper.onDepthFrame(depthFrame(roomFrames()[1], 1)));  // older

  ASSERT_TRUE(mapper.onFramePose(groundTruthPose(utimeOf(f), f.T_G_C)));
  EXPECT_FALSE(mapper.onFramePose(groundTruthPose(utimeOf(f), f.T_G_C)));
  EXPECT_FALSE(mapper.onFramePose(groundTruthPose(utimeOf(f) - 1, f.T_G_C)));
  TimedPose nan_pose = groundTruthPose(utimeOf(f) + 10, f.T_G_C);
  nan_pose.T_G_C =
      Transformationd(Eigen::Quaterniond::Identity(), Eigen::Vector3d::Constant(std::nan("")));
  EXPECT_FALSE(mapper.onFramePose(nan_pose));
  EXPECT_FALSE(mapper.onKeyframe(7, 0, nan_pose.T_G_C));
  ASSERT_TRUE(mapper.waitUntilIdle(kIdleTimeout));
  // The valid frame went in despite everything around it (a synthesised keyframe, id 2).
  EXPECT_EQ(mapper.status().frames_integrated, 1u);
  mapper.onKeyframe(2, 0, f.T_G_C);  // the synthesised keyframe's id again
  mapper.reportProblem(InputProblem::kDepthUndecodable, "truncated message");
  ASSERT_TRUE(mapper.waitUntilIdle(kIdleTimeout));

  const MapperStatus s = mapper.status();
  EXPECT_EQ(s.problem(InputProblem::kDepthInvalid), 4u);
  EXPECT_EQ(s.problem(InputProblem::kDepthOutOfOrder), 2u);
  EXPECT_EQ(s.problem(InputProblem::kDepthUndecodable), 1u);
  EXPECT_EQ(s.problem(InputProblem::kPoseDuplicate), 1u);
  EXPECT_EQ(s.problem(InputProblem::kPoseOutOfOrder), 1u);
  EXPECT_EQ(s.problem(InputProblem::kPoseInvalid), 1u);
  EXPECT_EQ(s.problem(InputProblem::kKeyframeInvalid), 1u);
  EXPECT_EQ(s.problem(InputProblem::kKeyframeDuplicate), 1u);
  EXPECT_EQ(s.frames_received, 8u);
  EXPECT_EQ(s.frames_rejected, 7u);
  EXPECT_EQ(s.frames_integrated, 1u);
  // Once per kind within the log interval.
  EXPECT_EQ(log.countContaining("(depth_invalid)"), 1u);
  EXPECT_EQ(log.countContaining("(depth_out_of_order)"), 1u);
  EXPECT_EQ(log.countContaining("(keyframe_duplicate)"), 1u);
}

TEST(MapperTest, TrackerModeFollowsKeyframesAndStartsANewSubvolumeAfterAJump) {
  test::TempDir dir("mapper");
  MapperConfig config = testConfig(dir.path());
  config.pose_source = PoseSource::kTracker;
  config.creation.max_keyframes_per_subvolume = 10;
  Mapper mapper(config);
  std::string error;
  ASSERT_TRUE(mapper.start(&error)) << error;
  const auto& frames = roomFrames();
  auto frameWithPose = [&](size_t i, bool jump = false, bool ok = true, int32_t epoch = 0) {
    ASSERT_TRUE(mapper.onDepthFrame(depthFrame(frames[i], static_cast<int64_t>(i))));
    TimedPose pose = groundTruthPose(utimeOf(frames[i]), frames[i].T_G_C);
    pose.jump = jump;
    pose.tracking_ok = ok;
    pose.epoch = epoch;
    ASSERT_TRUE(mapper.onFramePose(pose));
    ASSERT_TRUE(mapper.waitUntilIdle(kIdleTimeout));
  };
  // Before the first keyframe there is no subvolume: the frame waits for an anchor.
  frameWithPose(0);
  EXPECT_EQ(mapper.status().problem(InputProblem::kWaitingForAnchor), 1u);
  ASSERT_TRUE(mapper.onKeyframe(100, utimeOf(frames[1]), frames[1].T_G_C));
  ASSERT_TRUE(mapper.waitUntilIdle(kIdleTimeout));
  frameWithPose(1);
  frameWithPose(2);
  ASSERT_TRUE(mapper.onKeyframe(101, utimeOf(frames[2]), frames[2].T_G_C));  // joins submap 0
  frameWithPose(3, /*jump=*/false, /*ok=*/false);                            // tracking lost
  frameWithPose(4, /*jump=*/true);  // relocalised: waits for the next keyframe
  frameWithPose(5);
  EXPECT_EQ(mapper.collection().size(), 1u);
  ASSERT_TRUE(mapper.onKeyframe(102, utimeOf(frames[5]), frames[5].T_G_C));
  ASSERT_TRUE(mapper.waitUntilIdle(kIdleTimeout));
  frameWithPose(6);
  frameWithPose(7);

  const MapperStatus s = mapper.status();
  EXPECT_EQ(s.frames_integrated, 4u);  // 1, 2, 6, 7
  EXPECT_EQ(s.problem(InputProblem::kTrackingLost), 1u);
  EXPECT_EQ(s.problem(InputProblem::kWaitingForAnchor), 3u);  // 0, 4, 5
  ASSERT_EQ(mapper.collection().size(), 2u);
  EXPECT_EQ(mapper.collection().getSubmap(0)->keyframeIds(), (std::vector<KeyframeId>{100, 101}));
  EXPECT_EQ(mapper.collection().getSubmap(1)->anchorKeyframe(), 102);
  EXPECT_TRUE(mapper.collection().getSubmap(1)->T_G_M().isApprox(frames[5].T_G_C, 1e-12));
  EXPECT_GT(mapper.collection().getSubmap(1)->numBlocks(), 0u);
}

// Every new subvolume is logged with its anchor and the rule that started it. With
// subvolumes.revisit_anchor_distance_m, a keyframe that comes back near the anchor of an older
// subvolume of the same map epoch starts a new subvolume there; keyframes near the revisit
// subvolume's own anchor join it; a keyframe of another map epoch is not compared with the old
// epoch's anchors (a new map starts its own). max_anchor_distance_m still applies.
TEST(MapperTest, TrackerModeStartsASubvolumeWhereItRevisitsAnOlderAnchor) {
  test::TempDir dir("mapper");
  MapperConfig config = testConfig(dir.path());
  config.pose_source = PoseSource::kTracker;
  config.creation.max_keyframes_per_subvolume = 3;
  config.creation.revisit_anchor_distance_m = 1.0;
  config.creation.max_anchor_distance_m = 8.0;
  LogLines log;
  Mapper mapper(config, log.sink());
  std::string error;
  ASSERT_TRUE(mapper.start(&error)) << error;
  int64_t utime = 1000000;
  auto keyframe = [&](int64_t key, double x, double y) { keyframeAt(&mapper, &utime, key, x, y); };
  keyframe(0, 0.0, 0.0);  // subvolume 0 at x = 0 (no active subvolume)
  keyframe(1, 1.5, 0.0);
  keyframe(2, 3.0, 0.0);
  keyframe(3, 4.5, 0.0);  // subvolume 1 at x = 4.5 (keyframe limit)
  keyframe(4, 6.0, 0.0);
  keyframe(5, 0.4, 0.5);   // back near x = 0: subvolume 2 (revisit)
  keyframe(6, 0.2, 0.1);   // near anchors 0 and 2, which are 0.64 m apart: joins 2
  keyframe(7, 4.3, 0.2);   // near anchor 1: subvolume 3 (revisit)
  keyframe(8, 12.4, 0.2);  // 8.1 m from anchor 3: subvolume 4 (anchor distance)
  const std::optional<int64_t> other_epoch = epochKey(1, 0);
  ASSERT_TRUE(other_epoch.has_value());
  keyframe(*other_epoch, 0.0, 0.0);      // a new map: subvolume 5
  keyframe(*other_epoch + 1, 4.5, 0.0);  // near epoch 0's anchor 1, but another map: joins 5

  const auto ids = [&](SubmapId id) { return mapper.collection().getSubmap(id)->keyframeIds(); };
  ASSERT_EQ(mapper.collection().size(), 6u);
  EXPECT_EQ(ids(0), (std::vector<KeyframeId>{0, 1, 2}));
  EXPECT_EQ(ids(1), (std::vector<KeyframeId>{3, 4}));
  EXPECT_EQ(ids(2), (std::vector<KeyframeId>{5, 6}));
  EXPECT_EQ(ids(3), (std::vector<KeyframeId>{7}));
  EXPECT_EQ(ids(4), (std::vector<KeyframeId>{8}));
  EXPECT_EQ(ids(5), (std::vector<KeyframeId>{*other_epoch, *other_epoch + 1}));
  EXPECT_EQ(log.countContaining("(revisit)"), 2u);
  EXPECT_EQ(log.countContaining("subvolume 0 anchored at keyframe 0 (no active submap)"), 1u);
  EXPECT_EQ(log.countContaining("subvolume 1 anchored at keyframe 3 (keyframe limit)"), 1u);
  EXPECT_EQ(log.countContaining("subvolume 2 anchored at keyframe 5 (revisit)"), 1u);
  EXPECT_EQ(log.countContaining("subvolume 3 anchored at keyframe 7 (revisit)"), 1u);
  EXPECT_EQ(log.countContaining("subvolume 4 anchored at keyframe 8 (anchor distance)"), 1u);
  EXPECT_EQ(log.countContaining("subvolume 5 anchored at keyframe 0 of map epoch 1 (new map)"), 1u);
}

/// Covariance requests the mapper made, for a test to answer.
struct RequestLog {
  std::mutex mutex;
  std::vector<FusionCovarianceRequest> requests;
  Mapper::CovarianceRequester requester() {
    return [this](const FusionCovarianceRequest& r) {
      std::lock_guard<std::mutex> lock(mutex);
      requests.push_back(r);
    };
  }
  /// Waits up to 5 s for request number `n` (0-based).
  std::optional<FusionCovarianceRequest> waitFor(size_t n) {
    for (int i = 0; i < 500; ++i) {
      {
        std::lock_guard<std::mutex> lock(mutex);
        if (requests.size() > n) return requests[n];
      }
      std::this_thread::sleep_for(milliseconds(10));
    }
    return std::nullopt;
  }
};

/// `request` came and asks about exactly one pair: subvolumes `older` and `newer` through
/// their keyframes `older_keyframe` and `newer_keyframe`, sharing `shared` landmarks (< 0:
/// not checked).
void expectOnlyPair(const std::optional<FusionCovarianceRequest>& request, SubmapId older,
                    SubmapId newer, KeyframeId older_keyframe, KeyframeId newer_keyframe,
                    int shared = -1) {
  ASSERT_TRUE(request.has_value());
  ASSERT_EQ(request->pairs.size(), 1u);
  EXPECT_EQ(request->pairs[0].older, older);
  EXPECT_EQ(request->pairs[0].newer, newer);
  EXPECT_EQ(request->pairs[0].older_keyframe, older_keyframe);
  EXPECT_EQ(request->pairs[0].newer_keyframe, newer_keyframe);
  if (shared >= 0) {
    EXPECT_EQ(request->pairs[0].shared_landmarks, shared);
  }
}

/// A started tracker-mode mapper logging to `log`, its covariance requests going to
/// `requests` (both must outlive it); null when it did not start.
std::unique_ptr<Mapper> startTrackerModeMapper(MapperConfig config, LogLines* log,
                                               RequestLog* requests) {
  config.pose_source = PoseSource::kTracker;
  auto mapper = std::make_unique<Mapper>(config, log->sink());
  mapper->setCovarianceRequester(requests->requester());
  std::string error;
  if (!mapper->start(&error)) {
    ADD_FAILURE() << error;
    return nullptr;
  }
  return mapper;
}

// Integrates room frame i with its true pose, as the tracker reports a frame tracked in map
// `epoch` against keyframe `reference` (mapper key), and waits until the mapper is idle.
void integrateTrackedFrame(Mapper& mapper, size_t i, int64_t reference, int32_t epoch = 0,
                           bool jump = false) {
  const auto& frames = roomFrames();
  ASSERT_TRUE(mapper.onDepthFrame(depthFrame(frames[i], static_cast<int64_t>(i))));
  TimedPose pose = groundTruthPose(utimeOf(frames[i]), frames[i].T_G_C);
  pose.epoch = epoch;
  pose.reference_keyframe = reference;
  pose.jump = jump;
  ASSERT_TRUE(mapper.onFramePose(pose));
  ASSERT_TRUE(mapper.waitUntilIdle(kIdleTimeout));
}

// subvolumes.revisit_after_frames: frames tracked against a keyframe of an older subvolume
// (TimedPose::reference_keyframe) start, after that many in a row, a subvolume anchored at that
// subvolume's anchor (logged with its reason); a single stray frame does not. A pose batch
// moving the shared anchor moves both. Once the revisit subvolume is finished it is fused into
// the older one at once, without a covariance request (same anchor: the relative pose is the
// identity), and its keyframes join it.
TEST(MapperTest, TrackerModeAnchorsFramesTrackedInAnOlderSubvolumeToIt) {
  test::TempDir dir("mapper");
  MapperConfig config = testConfig(dir.path());
  config.creation.max_keyframes_per_subvolume = 2;
  config.creation.revisit_after_frames = 2;
  LogLines log;
  RequestLog requests;
  const std::unique_ptr<Mapper> started = startTrackerModeMapper(config, &log, &requests);
  ASSERT_NE(started, nullptr);
  Mapper& mapper = *started;
  const auto& frames = roomFrames();
  ASSERT_GE(frames.size(), 12u);
  auto frameWithReference = [&](size_t i, KeyframeId reference) {
    integrateTrackedFrame(mapper, i, reference);
  };
  auto keyframe = [&](KeyframeId id, size_t i) {
    ASSERT_TRUE(mapper.onKeyframe(id, utimeOf(frames[i]), frames[i].T_G_C));
    ASSERT_TRUE(mapper.waitUntilIdle(kIdleTimeout));
  };
  keyframe(100, 0);  // subvolume 0
  frameWithReference(0, 100);
  frameWithReference(1, 100);
  keyframe(101, 2);  // joins 0
  keyframe(102, 3);  // subvolume 1 (keyframe limit)
  frameWithReference(3, 102);
  frameWithReference(4, 101);  // one vote for subvolume 0
  frameWithReference(5, 102);  // back home: the votes start again
  frameWithReference(6, 101);
  EXPECT_EQ(mapper.collection().size(), 2u);
  frameWithReference(7, 100);  // the second vote in a row: subvolume 2, anchored at 100
  frameWithReference(8, 100);
  ASSERT_EQ(mapper.collection().size(), 3u);
  const std::shared_ptr<Submap> revisit = mapper.collection().getSubmap(2);
  ASSERT_NE(revisit, nullptr);
  EXPECT_EQ(revisit->anchorKeyframe(), 100);
  EXPECT_TRUE(revisit->T_G_M().isApprox(frames[0].T_G_C, 1e-12));
  EXPECT_GT(revisit->numBlocks(), 0u);  // frames 7 and 8
  EXPECT_EQ(log.countContaining("subvolume 2 anchored at keyframe 100 (tracked in an older "
                                "subvolume: revisit of subvolume 0)"),
            1u);
  EXPECT_EQ(mapper.status().frames_integrated, 8u);  // 0, 1, 3, ..., 8

  // A correction of keyframe 100 moves both subvolumes anchored there.
  const Transformationd moved =
      Transformationd(Eigen::Quaterniond::Identity(), Eigen::Vector3d(0.5, 0.0, 0.0)) *
      frames[0].T_G_C;
  mapper.onKeyframePoses({{100, moved}});
  ASSERT_TRUE(mapper.waitUntilIdle(kIdleTimeout));
  EXPECT_TRUE(mapper.collection().getSubmap(0)->T_G_M().isApprox(moved, 1e-12));
  EXPECT_TRUE(revisit->T_G_M().isApprox(moved, 1e-12));

  // Back to subvolume 1's keyframe: subvolume 3 anchored at 102; subvolume 2 is finished and
  // fused into 0 without a covariance.
  frameWithReference(9, 102);
  frameWithReference(10, 102);
  for (int i = 0; i < 500 && mapper.collection().getSubmap(2) != nullptr; ++i) {
    std::this_thread::sleep_for(milliseconds(10));
  }
  EXPECT_EQ(mapper.collection().submapIds(), (std::vector<SubmapId>{0, 1, 3}));
  EXPECT_EQ(mapper.collection().getSubmap(3)->anchorKeyframe(), 102);
  EXPECT_EQ(mapper.collection().getSubmap(0)->keyframeIds(), (std::vector<KeyframeId>{100, 101}));
  const MapperStatus s = mapper.status();
  EXPECT_EQ(s.fusion.same_anchor, 1u);
  EXPECT_EQ(s.fusion.fused, 1u);
  EXPECT_EQ(s.fusion.accepted, 0u);
  EXPECT_EQ(log.countContaining("fusion accepted: subvolume 2 into 0 without a covariance (both "
                                "anchored at keyframe 100)"),
            1u);
  std::lock_guard<std::mutex> lock(requests.mutex);
  for (const FusionCovarianceRequest& r : requests.requests) {
    for (const FusionPair& p : r.pairs) EXPECT_NE(p.older_keyframe, p.newer_keyframe);
  }
}

// After a tracking jump (a loop closure or a relocalization), frames wait for the next
// keyframe to anchor a new subvolume; a frame tracked against a keyframe of an older
// subvolume starts a revisit subvolume at that subvolume's anchor at once instead, so the
// frames of a known place are integrated, not rejected.
TEST(MapperTest, TrackerModeJumpIntoAnOlderSubvolumeIsIntegratedAtOnce) {
  const auto& frames = roomFrames();
  ASSERT_GE(frames.size(), 8u);
  // Subvolumes 0 and 1 (anchored at keyframes 100 and 101), a frame tracked against 101, a
  // jump tracked against 101, then two frames tracked against 100.
  // (The directory, log and request log outlive the mapper: it writes and calls into them;
  // members are destroyed in reverse order.)
  struct Run {
    test::TempDir dir{"mapper"};
    LogLines log;
    RequestLog requests;
    std::unique_ptr<Mapper> mapper;
  };
  auto drive = [&](int revisit_after_frames, Run* run) {
    MapperConfig config = testConfig(run->dir.path());
    config.creation.max_keyframes_per_subvolume = 1;
    config.creation.revisit_after_frames = revisit_after_frames;
    run->mapper = startTrackerModeMapper(config, &run->log, &run->requests);
    ASSERT_NE(run->mapper, nullptr);
    Mapper& mapper = *run->mapper;
    EXPECT_TRUE(mapper.onKeyframe(100, utimeOf(frames[0]), frames[0].T_G_C));
    EXPECT_TRUE(mapper.onKeyframe(101, utimeOf(frames[1]), frames[1].T_G_C));
    EXPECT_TRUE(mapper.waitUntilIdle(kIdleTimeout));
    integrateTrackedFrame(mapper, 1, 101);
    // A jump tracked against the active subvolume's own keyframe: the frame waits.
    integrateTrackedFrame(mapper, 2, 101, 0, true);
    EXPECT_EQ(mapper.collection().size(), 2u);
    EXPECT_EQ(mapper.status().frames_integrated, 1u);
    integrateTrackedFrame(mapper, 3, 100);
    integrateTrackedFrame(mapper, 4, 100);
  };
  // Tracked against keyframe 100 (subvolume 0) while the jump waits for its anchor: a revisit
  // subvolume anchored at 100 takes the frame and the next one.
  Run on;
  drive(10, &on);
  ASSERT_NE(on.mapper, nullptr);
  const Mapper& mapper = *on.mapper;
  ASSERT_EQ(mapper.collection().size(), 3u);
  const std::shared_ptr<Submap> revisit = mapper.collection().getSubmap(2);
  ASSERT_NE(revisit, nullptr);
  EXPECT_EQ(revisit->anchorKeyframe(), 100);
  EXPECT_TRUE(revisit->T_G_M().isApprox(frames[0].T_G_C, 1e-12));
  EXPECT_GT(revisit->numBlocks(), 0u);
  EXPECT_EQ(mapper.status().frames_integrated, 3u);  // 1, 3 and 4
  EXPECT_EQ(on.log.countContaining("subvolume 2 anchored at keyframe 100 (tracked in an older "
                                   "subvolume after a jump: revisit of subvolume 0)"),
            1u);
  // With the frames rule off, the same frames wait for a keyframe.
  Run off;
  drive(0, &off);
  ASSERT_NE(off.mapper, nullptr);
  EXPECT_EQ(off.mapper->collection().size(), 2u);
  EXPECT_EQ(off.mapper->status().frames_integrated, 1u);
}

// A reference keyframe that no subvolume holds, or one of another map epoch than the active
// subvolume's, never starts a revisit subvolume.
TEST(MapperTest, RevisitAnchoringIgnoresUnknownAndOtherEpochReferences) {
  test::TempDir dir("mapper");
  MapperConfig config = testConfig(dir.path());
  config.creation.max_keyframes_per_subvolume = 1;
  config.creation.revisit_after_frames = 1;
  LogLines log;
  RequestLog requests;
  const std::unique_ptr<Mapper> started = startTrackerModeMapper(config, &log, &requests);
  ASSERT_NE(started, nullptr);
  Mapper& mapper = *started;
  const auto& frames = roomFrames();
  const std::optional<int64_t> epoch1 = epochKey(1, 0);
  ASSERT_TRUE(epoch1.has_value());
  ASSERT_TRUE(mapper.onKeyframe(0, utimeOf(frames[0]), frames[0].T_G_C));        // subvolume 0
  ASSERT_TRUE(mapper.onKeyframe(*epoch1, utimeOf(frames[1]), frames[1].T_G_C));  // 1: new map
  ASSERT_TRUE(mapper.waitUntilIdle(kIdleTimeout));
  for (size_t i = 1; i < 5; ++i) {
    integrateTrackedFrame(mapper, i, i % 2 == 0 ? 0 : 12345, 1);  // epoch 0's keyframe, or unknown
  }
  EXPECT_EQ(mapper.collection().submapIds(), (std::vector<SubmapId>{0, 1}));
  EXPECT_EQ(mapper.status().frames_integrated, 4u);
  EXPECT_EQ(log.countContaining("tracked in an older subvolume"), 0u);
}

std::vector<uint64_t> landmarkRange(uint64_t begin, uint64_t end) {
  std::vector<uint64_t> ids;
  for (uint64_t i = begin; i < end; ++i) ids.push_back(i);
  return ids;
}

// Map maintenance end to end in one process: keyframes carry landmark ids, two finished
// subvolumes that share enough landmarks become a candidate, the mapper asks for
// Sigma_{newer anchor | older anchor}, and an answer with q >= q_min makes the worker fuse the
// newer subvolume into the older (its keyframes join it, pose batches naming them stay
// known). An answer with q < q_min fuses nothing. The active subvolume is never proposed.
TEST(MapperTest, TrackerModeFusesSubvolumesWhoseCovarianceIsSmallEnough) {
  test::TempDir dir("mapper");
  MapperConfig config = testConfig(dir.path());
  config.creation.max_keyframes_per_subvolume = 2;
  config.maintenance.q_min = 1e4;
  LogLines log;
  RequestLog requests;
  const std::unique_ptr<Mapper> started = startTrackerModeMapper(config, &log, &requests);
  ASSERT_NE(started, nullptr);
  Mapper& mapper = *started;
  const auto& frames = roomFrames();
  auto frameWithPose = [&](size_t i) {
    ASSERT_TRUE(mapper.onDepthFrame(depthFrame(frames[i], static_cast<int64_t>(i))));
    ASSERT_TRUE(mapper.onFramePose(groundTruthPose(utimeOf(frames[i]), frames[i].T_G_C)));
    ASSERT_TRUE(mapper.waitUntilIdle(kIdleTimeout));
  };
  auto keyframe = [&](KeyframeId id, size_t frame, uint64_t first, uint64_t last) {
    ASSERT_TRUE(mapper.onKeyframe(id, utimeOf(frames[frame]), frames[frame].T_G_C,
                                  landmarkRange(first, last)));
    ASSERT_TRUE(mapper.waitUntilIdle(kIdleTimeout));
  };
  // Subvolume 0: keyframes 100, 101 see landmarks [0, 100); subvolume 1: 102, 103 see
  // [50, 150) (50 shared, half of each set); subvolume 2: 104 sees [1000, 1100).
  keyframe(100, 0, 0, 100);
  for (size_t i = 0; i < 3; ++i) frameWithPose(i);
  keyframe(101, 2, 0, 100);
  keyframe(102, 3, 50, 150);
  for (size_t i = 3; i < 6; ++i) frameWithPose(i);
  keyframe(103, 5, 50, 150);
  {
    // The maintenance thread asks right after each item, before it is idle: nothing yet,
    // because subvolume 1 is active.
    std::lock_guard<std::mutex> lock(requests.mutex);
    EXPECT_TRUE(requests.requests.empty());
  }
  keyframe(104, 6, 1000, 1100);
  frameWithPose(6);
  ASSERT_EQ(mapper.collection().size(), 3u);
  const size_t blocks_0 = mapper.collection().getSubmap(0)->numBlocks();
  const size_t blocks_1 = mapper.collection().getSubmap(1)->numBlocks();

  const std::optional<FusionCovarianceRequest> request = requests.waitFor(0);
  expectOnlyPair(request, 0, 1, 100, 102, 50);
  ASSERT_TRUE(request.has_value());

  mapper.onCovarianceReply(request->request_id, {FusionCovarianceAnswer{true, "", 2e4}});
  ASSERT_TRUE(mapper.waitUntilIdle(milliseconds(20000)));
  ASSERT_EQ(mapper.collection().size(), 2u);
  EXPECT_EQ(mapper.collection().getSubmap(1), nullptr);
  const std::shared_ptr<Submap> fused = mapper.collection().getSubmap(0);
  EXPECT_EQ(fused->keyframeIds(), (std::vector<KeyframeId>{100, 101, 102, 103}));
  EXPECT_GT(fused->numBlocks(), std::max(blocks_0, blocks_1));
  EXPECT_EQ(log.countContaining("fused subvolume 1 into 0"), 1u);
  MapperStatus s = mapper.status();
  EXPECT_EQ(s.fusion.candidates, 1u);
  EXPECT_EQ(s.fusion.requested, 1u);
  EXPECT_EQ(s.fusion.accepted, 1u);
  EXPECT_EQ(s.fusion.fused, 1u);
  EXPECT_EQ(s.fusion.rejected_by_q, 0u);
  // A correction naming the absorbed subvolume's anchor: known, moves nothing.
  mapper.onKeyframePoses({{102, frames[3].T_G_C}});
  ASSERT_TRUE(mapper.waitUntilIdle(kIdleTimeout));
  EXPECT_EQ(mapper.status().problem(InputProblem::kKeyframePoseUnknown), 0u);

  // Keyframe 105 joins subvolume 2 and sees [0, 100) too: 2 shares 100 landmarks with 0
  // once 106 anchors subvolume 3 and 2 is finished. Its answer is below q_min.
  keyframe(105, 7, 0, 100);
  keyframe(106, 8, 2000, 2100);
  frameWithPose(8);
  ASSERT_EQ(mapper.collection().size(), 3u);  // 0, 2, 3
  const std::optional<FusionCovarianceRequest> second = requests.waitFor(1);
  expectOnlyPair(second, 0, 2, 100, 104, 100);  // asked through the anchors
  ASSERT_TRUE(second.has_value());
  mapper.onCovarianceReply(second->request_id, {FusionCovarianceAnswer{true, "", 5e3}});
  ASSERT_TRUE(mapper.waitUntilIdle(kIdleTimeout));
  s = mapper.status();
  EXPECT_EQ(s.fusion.rejected_by_q, 1u);
  EXPECT_EQ(s.fusion.fused, 1u);
  EXPECT_EQ(mapper.collection().size(), 3u);
}

// On the input clock (deterministic replay) map maintenance asks only after an input: a pair
// that becomes free when a fusion ends after the last input waits for the next one, or for
// maintenanceTick(), which asks at once (the steady clock's 0.25 s tick does it by itself).
TEST(MapperTest, MaintenanceTickAsksForPairsFreedAfterTheLastInput) {
  test::TempDir dir("mapper");
  MapperConfig config = testConfig(dir.path());
  config.creation.max_keyframes_per_subvolume = 1;
  config.maintenance_clock = MaintenanceClock::kInput;
  LogLines log;
  RequestLog requests;
  const std::unique_ptr<Mapper> started = startTrackerModeMapper(config, &log, &requests);
  ASSERT_NE(started, nullptr);
  Mapper& mapper = *started;
  const auto& frames = roomFrames();
  // Subvolumes 0, 1, 2 (keyframes 100, 101, 102) all see landmarks [0, 100); 3 sees others.
  auto subvolume = [&](KeyframeId id, size_t first_frame, uint64_t first, uint64_t last) {
    ASSERT_TRUE(mapper.onKeyframe(id, utimeOf(frames[first_frame]), frames[first_frame].T_G_C,
                                  landmarkRange(first, last)));
    for (size_t i = first_frame; i < first_frame + 2; ++i) {
      ASSERT_TRUE(mapper.onDepthFrame(depthFrame(frames[i], static_cast<int64_t>(i))));
      ASSERT_TRUE(mapper.onFramePose(groundTruthPose(utimeOf(frames[i]), frames[i].T_G_C)));
      ASSERT_TRUE(mapper.waitUntilIdle(kIdleTimeout));
    }
  };
  subvolume(100, 0, 0, 100);
  subvolume(101, 2, 0, 100);
  subvolume(102, 4, 0, 100);  // 1 is finished: the pair 0-1 is asked
  const std::optional<FusionCovarianceRequest> first = requests.waitFor(0);
  expectOnlyPair(first, 0, 1, 100, 101);
  ASSERT_TRUE(first.has_value());
  subvolume(103, 6, 5000, 5100);  // 2 is finished while that request is in flight
  mapper.onCovarianceReply(first->request_id, {FusionCovarianceAnswer{true, "", 1e5}});
  ASSERT_TRUE(mapper.waitUntilIdle(milliseconds(20000)));
  EXPECT_EQ(mapper.status().fusion.fused, 1u);
  {
    // 0-2 became free when the fusion ended, after the last input: not asked.
    std::lock_guard<std::mutex> lock(requests.mutex);
    EXPECT_EQ(requests.requests.size(), 1u);
  }
  mapper.maintenanceTick();
  expectOnlyPair(requests.waitFor(1), 0, 2, 100, 102);
  // A second tick with the request still in flight asks nothing more.
  mapper.maintenanceTick();
  ASSERT_TRUE(mapper.waitUntilIdle(kIdleTimeout));
  std::lock_guard<std::mutex> lock(requests.mutex);
  EXPECT_EQ(requests.requests.size(), 2u);
}

TEST(MapperTest, StopAppliesTheKeyframesStillQueued) {
  test::TempDir dir("mapper");
  MapperConfig config = testConfig(dir.path());
  config.pose_source = PoseSource::kTracker;
  config.creation.max_keyframes_per_subvolume = 1000;
  Mapper mapper(config, [](const std::string&) {});
  std::string error;
  ASSERT_TRUE(mapper.start(&error)) << error;
  const auto& frames = roomFrames();
  constexpr KeyframeId kCount = 200;  // below the maintenance queue's capacity
  for (KeyframeId id = 0; id < kCount; ++id) {
    ASSERT_TRUE(mapper.onKeyframe(id, 1000 + static_cast<int64_t>(id), frames[0].T_G_C));
  }
  mapper.stop();  // no waitUntilIdle: whatever is still queued must be applied by stop()
  ASSERT_EQ(mapper.collection().size(), 1u);
  EXPECT_EQ(mapper.collection().getSubmap(0)->keyframeIds().size(), kCount);
}

// Scheduling of every thread of this process: (policy, niceness) per thread id.
std::vector<std::pair<int, int>> threadSchedules() {
  std::vector<std::pair<int, int>> result;
  for (const auto& entry : std::filesystem::directory_iterator("/proc/self/task")) {
    const pid_t tid = static_cast<pid_t>(std::stol(entry.path().filename().string()));
    errno = 0;
    const int nice = getpriority(PRIO_PROCESS, static_cast<id_t>(tid));
    result.emplace_back(sched_getscheduler(tid), nice);
  }
  return result;
}

TEST(MapperTest, WorkerThreadRunsAtIdlePriorityAndTheIntegratorAtItsNiceness) {
  test::TempDir dir("mapper");
  MapperConfig config = testConfig(dir.path());
  config.worker_niceness = 7;
  config.worker_sched_idle = true;
  config.integrator_niceness = 3;
  LogLines lines;
  Mapper mapper(config, lines.sink());
  std::string error;
  ASSERT_TRUE(mapper.start(&error)) << error;
  const std::pair<int, int> expected{SCHED_IDLE, 7};
  const std::pair<int, int> integrator{SCHED_OTHER, 3};
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(5);
  std::vector<std::pair<int, int>> schedules;
  do {  // the worker and the integrator lower their own priority as they start
    schedules = threadSchedules();
    if (std::count(schedules.begin(), schedules.end(), expected) == 1 &&
        std::count(schedules.begin(), schedules.end(), integrator) == 1) {
      break;
    }
    std::this_thread::sleep_for(milliseconds(5));
  } while (std::chrono::steady_clock::now() < deadline);
  EXPECT_EQ(std::count(schedules.begin(), schedules.end(), expected), 1) << [&] {
    std::string s;
    for (const auto& [policy, nice] : schedules)
      s += " (" + std::to_string(policy) + ", " + std::to_string(nice) + ")";
    std::lock_guard<std::mutex> lock(lines.mutex);
    for (const auto& l : lines.lines) s += "\n" + l;
    return s;
  }();
  // The integrator runs at integrator_niceness (it yields to the tracker under overload);
  // the maintenance thread keeps the process's normal priority.
  EXPECT_EQ(std::count(schedules.begin(), schedules.end(), integrator), 1);
  const std::pair<int, int> normal{SCHED_OTHER, getpriority(PRIO_PROCESS, 0)};
  EXPECT_GE(std::count(schedules.begin(), schedules.end(), normal), 2);  // main + maintenance
  mapper.stop();
}

TEST(MapperTest, InterpolatesPosesBetweenFrameTimes) {
  test::TempDir dir("mapper");
  Mapper mapper(testConfig(dir.path()));
  std::string error;
  ASSERT_TRUE(mapper.start(&error)) << error;
  const auto& frames = roomFrames();
  // Poses 100 ms apart around the frame, none at its time stamp.
  ASSERT_TRUE(mapper.onDepthFrame(depthFrame(frames[1], 1)));
  ASSERT_TRUE(mapper.onFramePose(groundTruthPose(utimeOf(frames[0]), frames[0].T_G_C)));
  ASSERT_TRUE(mapper.onFramePose(groundTruthPose(utimeOf(frames[2]), frames[2].T_G_C)));
  ASSERT_TRUE(mapper.waitUntilIdle(kIdleTimeout));
  EXPECT_EQ(mapper.status().frames_integrated, 1u);
  // The synthesised keyframe's pose is the interpolated one.
  const Transformationd expected =
      Transformationd::interpolate(frames[0].T_G_C, frames[2].T_G_C, 0.5);
  EXPECT_TRUE(mapper.collection().getSubmap(0)->T_G_M().isApprox(expected, 1e-9));
}

TEST(MapperTest, ARestartedSourceStartsAfreshInsteadOfBeingRejected) {
  test::TempDir dir("mapper");
  MapperConfig config = testConfig(dir.path());
  config.restart_after_backwards_s = 0.3;
  LogLines log;
  Mapper mapper(config, log.sink());
  std::string error;
  ASSERT_TRUE(mapper.start(&error)) << error;
  feed(&mapper, 0, 9);  // 0 .. 0.8 s
  // A small step back is out of order, not a restart.
  EXPECT_FALSE(mapper.onDepthFrame(depthFrame(roomFrames()[7], 7)));
  EXPECT_FALSE(
      mapper.onFramePose(groundTruthPose(utimeOf(roomFrames()[7]), roomFrames()[7].T_G_C)));
  // The capture runs again from time 0 with frame ids from 0: every frame is integrated.
  feed(&mapper, 0, 6);
  const MapperStatus s = mapper.status();
  EXPECT_EQ(s.source_restarts, 1u);  // seen on depth, which clears the old stream's poses too
  EXPECT_EQ(s.frames_integrated, 15u);
  EXPECT_EQ(s.problem(InputProblem::kDepthOutOfOrder), 1u);
  EXPECT_EQ(s.problem(InputProblem::kPoseOutOfOrder), 1u);
  EXPECT_EQ(s.problem(InputProblem::kKeyframeDuplicate), 0u);
  // Synthesised keyframes of the second run got fresh ids (frame ids 0 and 3 were taken).
  EXPECT_EQ(s.keyframes_applied, 5u);  // 0, 3, 6, then 7, 8 for frames 0, 3 of the rerun
  EXPECT_EQ(log.countContaining("source restarted"), 1u);
}

TEST(MapperTest, StopIsIdempotentAndAnswersLateCommands) {
  test::TempDir dir("mapper");
  Mapper mapper(testConfig(dir.path()));
  std::string error;
  ASSERT_TRUE(mapper.start(&error)) << error;
  feed(&mapper, 0, 2);
  mapper.stop();
  mapper.stop();
  const MapperReply late = runCommand(&mapper, "export_mesh", "late.ply");
  EXPECT_FALSE(late.ok);
  EXPECT_EQ(late.message, "mapper stopping");
}

TEST(MapperTest, RejectsInvalidConfigAndUncreatableOutputDir) {
  MapperConfig config;
  config.keyframe_every_n_frames = 0;
  EXPECT_THROW(Mapper{config}, std::invalid_argument);
  config = MapperConfig{};
  config.layer.voxel_size = 0.1f;  // truncation 0.12 m stays valid; 0.05 would not
  config.integrator.truncation_distance_m = 0.05f;
  EXPECT_THROW(Mapper{config}, std::invalid_argument);
  test::TempDir dir("mapper");
  dir.write("file", "x");
  config = testConfig(dir.path() / "file" / "sub");
  Mapper mapper(config);
  std::string error;
  EXPECT_FALSE(mapper.start(&error));
  EXPECT_NE(error.find("output directory"), std::string::npos);
}

TEST(MapperTest, SubmapColoursDiffer) {
  std::set<std::tuple<int, int, int>> colours;
  for (SubmapId id = 0; id < 32; ++id) {
    const Color c = submapColor(id);
    colours.insert({c.r, c.g, c.b});
  }
  EXPECT_EQ(colours.size(), 32u);
}

// A map saved over the command channel and loaded into a fresh mapper (load_map on an
// empty mapper, and loadMap before start() as cblox-mapper --load-map does) exports the same
// mesh and has the same subvolumes and blocks; the loaded map can be continued.
TEST(MapperTest, SavedMapLoadsIntoAFreshMapperWithTheSameMesh) {
  test::TempDir dir("mapper_save");
  Mapper saver(testConfig(dir.path() / "a"));
  std::string error;
  ASSERT_TRUE(saver.start(&error)) << error;
  feed(&saver, 0, 18);
  const MapperStatus saved_status = saver.status();
  ASSERT_GE(saved_status.num_submaps, 2u);
  const MapperReply saved = runCommand(&saver, "save_map", "maps/run1");
  ASSERT_TRUE(saved.ok) << saved.message;
  const std::filesystem::path map_dir = dir.path() / "a" / "maps" / "run1";
  EXPECT_EQ(saved.value("path"), map_dir.string());
  EXPECT_EQ(saved.value("submaps"), std::to_string(saved_status.num_submaps));
  EXPECT_EQ(saved.value("blocks"), std::to_string(saved_status.num_blocks));
  uint64_t bytes = 0;
  for (const auto& entry : std::filesystem::directory_iterator(map_dir)) {
    bytes += entry.file_size();
  }
  EXPECT_EQ(saved.value("bytes"), std::to_string(bytes));
  EXPECT_FALSE(saved.value("seconds").empty());
  ASSERT_TRUE(runCommand(&saver, "export_mesh", "saved.ply").ok);
  const std::string saved_mesh = test::readFile((dir.path() / "a" / "saved.ply").string());
  ASSERT_FALSE(saved_mesh.empty());

  // load_map over the command channel, into a mapper that has not seen a frame.
  {
    Mapper loader(testConfig(dir.path() / "b"));
    ASSERT_TRUE(loader.start(&error)) << error;
    const MapperReply loaded = runCommand(&loader, "load_map", map_dir.string());
    ASSERT_TRUE(loaded.ok) << loaded.message;
    EXPECT_NE(loaded.message.find("covisibility restored"), std::string::npos);
    EXPECT_EQ(loaded.value("submaps"), saved.value("submaps"));
    EXPECT_EQ(loaded.value("blocks"), saved.value("blocks"));
    const MapperStatus s = loader.status();
    EXPECT_EQ(s.num_submaps, saved_status.num_submaps);
    EXPECT_EQ(s.num_blocks, saved_status.num_blocks);
    EXPECT_EQ(s.active_submap_id, saved_status.active_submap_id);
    ASSERT_TRUE(runCommand(&loader, "export_mesh", "loaded.ply").ok);
    EXPECT_TRUE(test::readFile((dir.path() / "b" / "loaded.ply").string()) == saved_mesh);

    // The loaded map goes on: the loaded keyframe ids are known, so the synthesised keyframes
    // of the new frames (ids 0, 3, ... again) are not duplicates.
    feed(&loader, 0, 9);
    const MapperStatus after = loader.status();
    EXPECT_EQ(after.frames_integrated, 9u);
    EXPECT_EQ(after.problem(InputProblem::kKeyframeDuplicate), 0u);
    EXPECT_GT(after.num_submaps, saved_status.num_submaps);
  }

  // cblox-mapper --load-map: loadMap before start().
  Mapper at_start(testConfig(dir.path() / "c"));
  const MapperReply loaded = at_start.loadMap(map_dir.string());
  ASSERT_TRUE(loaded.ok) << loaded.message;
  ASSERT_TRUE(at_start.start(&error)) << error;
  EXPECT_EQ(at_start.status().num_submaps, saved_status.num_submaps);
  EXPECT_EQ(at_start.status().num_blocks, saved_status.num_blocks);
  ASSERT_TRUE(runCommand(&at_start, "export_mesh", "loaded.ply").ok);
  EXPECT_TRUE(test::readFile((dir.path() / "c" / "loaded.ply").string()) == saved_mesh);
}

// save_map is confined like the exports; load_map is refused on a map that is not empty, on
// another layer geometry and on a corrupt map (the file named), and the mapper still serves.
TEST(MapperTest, SaveAndLoadMapRefusals) {
  test::TempDir dir("mapper_save_refused");
  Mapper mapper(testConfig(dir.path() / "a"));
  std::string error;
  ASSERT_TRUE(mapper.start(&error)) << error;
  feed(&mapper, 0, 12);
  const std::string escape = dir.path().filename().string() + "_escape";
  const MapperReply escaped = runCommand(&mapper, "save_map", "../" + escape);
  EXPECT_FALSE(escaped.ok);
  EXPECT_FALSE(std::filesystem::exists(dir.path() / escape));
  EXPECT_FALSE(std::filesystem::exists(dir.path().parent_path() / escape));
  EXPECT_FALSE(runCommand(&mapper, "save_map").ok);  // no path
  ASSERT_TRUE(runCommand(&mapper, "save_map", "map").ok);
  const std::filesystem::path map_dir = dir.path() / "a" / "map";

  const MapperReply not_empty = runCommand(&mapper, "load_map", map_dir.string());
  EXPECT_FALSE(not_empty.ok);
  EXPECT_NE(not_empty.message.find("the map is not empty ("), std::string::npos)
      << not_empty.message;
  EXPECT_NE(not_empty.message.find("load a map into a fresh mapper"), std::string::npos);

  MapperConfig coarse = testConfig(dir.path() / "b");
  coarse.layer.voxel_size = 0.05f;
  Mapper other_geometry(coarse);
  const MapperReply geometry = other_geometry.loadMap(map_dir.string());
  EXPECT_FALSE(geometry.ok);
  EXPECT_NE(geometry.message.find("0.0500"), std::string::npos) << geometry.message;
  EXPECT_NE(geometry.message.find("0.0400"), std::string::npos) << geometry.message;
  EXPECT_EQ(other_geometry.status().num_submaps, 0u);

  // Flip one byte in the middle of a submap file.
  std::filesystem::path submap_file;
  for (const auto& entry : std::filesystem::directory_iterator(map_dir)) {
    if (entry.path().extension() == ".cbsub") submap_file = entry.path();
  }
  ASSERT_FALSE(submap_file.empty());
  {
    std::fstream f(submap_file, std::ios::in | std::ios::out | std::ios::binary);
    const auto middle = static_cast<std::streamoff>(std::filesystem::file_size(submap_file) / 2);
    f.seekg(middle);
    char byte = 0;
    f.read(&byte, 1);
    byte = static_cast<char>(byte ^ 0x5a);
    f.seekp(middle);
    f.write(&byte, 1);
  }
  Mapper fresh(testConfig(dir.path() / "c"));
  ASSERT_TRUE(fresh.start(&error)) << error;
  const MapperReply corrupt = runCommand(&fresh, "load_map", map_dir.string());
  EXPECT_FALSE(corrupt.ok);
  EXPECT_NE(corrupt.message.find(submap_file.filename().string()), std::string::npos)
      << corrupt.message;
  EXPECT_EQ(fresh.status().num_submaps, 0u);
  const MapperReply status = runCommand(&fresh, "status");
  EXPECT_TRUE(status.ok);
  EXPECT_EQ(status.value("subvolumes"), "0");
  EXPECT_FALSE(fresh.loadMap((dir.path() / "nothing_here").string()).ok);
  feed(&fresh, 0, 3);  // still integrating
  EXPECT_EQ(fresh.status().frames_integrated, 3u);
}

/// Waits (up to 30 s) until `mapper` has committed at least `n` periodic checkpoints.
bool waitForCheckpoints(const Mapper& mapper, uint64_t n) {
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(30);
  while (mapper.status().checkpoints_written < n) {
    if (std::chrono::steady_clock::now() > deadline) return false;
    std::this_thread::sleep_for(milliseconds(5));
  }
  return true;
}

MapperConfig checkpointConfig(const std::filesystem::path& output_dir,
                              const std::filesystem::path& checkpoint_dir) {
  MapperConfig config = testConfig(output_dir);
  config.checkpoint.dir = checkpoint_dir.string();
  config.checkpoint.period_s = 0.05;
  return config;
}

// The worker writes a checkpoint every checkpoint.period_s (counted in status); a new mapper
// resumes from it (as cblox-mapper does at start) with the subvolumes, blocks and exported mesh
// of the first mapper at that checkpoint, and can go on mapping.
TEST(MapperTest, PeriodicCheckpointResumesIntoANewMapperWithTheSameMesh) {
  test::TempDir dir("mapper_checkpoint");
  const std::filesystem::path checkpoint_dir = dir.path() / "ckpt";
  std::string saved_mesh;
  MapperStatus saved_status;
  {
    LogLines log;
    Mapper first(checkpointConfig(dir.path() / "a", checkpoint_dir), log.sink());
    EXPECT_FALSE(first.resumeFromCheckpoint());  // first run: no manifest yet
    std::string error;
    ASSERT_TRUE(first.start(&error)) << error;
    feed(&first, 0, 18);
    // Two more checkpoints: at least one began after the last frame, and nothing changes the
    // map meanwhile (no fusions without a covariance requester).
    const uint64_t after_feed = first.status().checkpoints_written;
    ASSERT_TRUE(waitForCheckpoints(first, after_feed + 2));
    saved_status = first.status();
    EXPECT_GE(saved_status.num_submaps, 2u);
    EXPECT_EQ(saved_status.checkpoint_failures, 0u);
    EXPECT_GT(saved_status.last_checkpoint_ms, 0.0f);
    EXPECT_EQ(log.countContaining("first checkpoint into " + checkpoint_dir.string()), 1u);
    const MapperReply status = runCommand(&first, "status");
    EXPECT_NE(status.value("checkpoints_written"), "");
    EXPECT_EQ(status.value("checkpoint_failures"), "0");
    EXPECT_NE(status.value("last_checkpoint_ms"), "");
    ASSERT_TRUE(runCommand(&first, "export_mesh", "first.ply").ok);
    saved_mesh = test::readFile((dir.path() / "a" / "first.ply").string());
    ASSERT_FALSE(saved_mesh.empty());
    first.stop();
  }
  ASSERT_TRUE(std::filesystem::exists(checkpoint_dir / kManifestFileName));

  Mapper resumed(checkpointConfig(dir.path() / "b", checkpoint_dir));
  const std::optional<MapperReply> reply = resumed.resumeFromCheckpoint();
  ASSERT_TRUE(reply);
  ASSERT_TRUE(reply->ok) << reply->message;
  EXPECT_EQ(reply->message.rfind("resumed from " + checkpoint_dir.string() + " generation " +
                                     reply->value("generation") + ": " +
                                     std::to_string(saved_status.num_submaps) + " subvolumes",
                                 0),
            0u)
      << reply->message;
  std::string error;
  ASSERT_TRUE(resumed.start(&error)) << error;
  EXPECT_EQ(resumed.status().num_submaps, saved_status.num_submaps);
  EXPECT_EQ(resumed.status().num_blocks, saved_status.num_blocks);
  EXPECT_EQ(resumed.status().active_submap_id, saved_status.active_submap_id);
  ASSERT_TRUE(runCommand(&resumed, "export_mesh", "resumed.ply").ok);
  EXPECT_TRUE(test::readFile((dir.path() / "b" / "resumed.ply").string()) == saved_mesh);
  // It goes on, and checkpoints into the same directory again.
  const uint64_t before = resumed.status().checkpoints_written;
  feed(&resumed, 18, 24);
  ASSERT_TRUE(waitForCheckpoints(resumed, before + 2));
  EXPECT_EQ(resumed.status().checkpoint_failures, 0u);
}

// A clean stop writes a last checkpoint: what was integrated after the last periodic one
// (here: none was due yet, the period being an hour) is not lost.
TEST(MapperTest, CleanStopWritesALastCheckpoint) {
  test::TempDir dir("mapper_checkpoint_stop");
  const std::filesystem::path checkpoint_dir = dir.path() / "ckpt";
  MapperConfig config = checkpointConfig(dir.path() / "a", checkpoint_dir);
  config.checkpoint.period_s = 3600.0;
  std::string saved_mesh;
  MapperStatus saved_status;
  {
    Mapper first(config);
    std::string error;
    ASSERT_TRUE(first.start(&error)) << error;
    feed(&first, 0, 18);
    EXPECT_EQ(first.status().checkpoints_written, 0u);
    ASSERT_TRUE(runCommand(&first, "export_mesh", "first.ply").ok);
    saved_mesh = test::readFile((dir.path() / "a" / "first.ply").string());
    saved_status = first.status();
    first.stop();
    EXPECT_EQ(first.status().checkpoints_written, 1u);
  }
  Mapper resumed(checkpointConfig(dir.path() / "b", checkpoint_dir));
  const std::optional<MapperReply> reply = resumed.resumeFromCheckpoint();
  ASSERT_TRUE(reply);
  ASSERT_TRUE(reply->ok) << reply->message;
  std::string error;
  ASSERT_TRUE(resumed.start(&error)) << error;
  EXPECT_EQ(resumed.status().num_submaps, saved_status.num_submaps);
  EXPECT_EQ(resumed.status().num_blocks, saved_status.num_blocks);
  ASSERT_TRUE(runCommand(&resumed, "export_mesh", "resumed.ply").ok);
  EXPECT_TRUE(test::readFile((dir.path() / "b" / "resumed.ply").string()) == saved_mesh);
}

// Map maintenance survives a restart: the covisibility graph (landmark sets) and the back-off
// of a pair rejected by q are in the checkpoint (manifest version 2), so the resumed mapper
// has the same edges and waits before asking for the rejected pair again. The status says
// which generation is committed.
TEST(MapperTest, ResumeRestoresTheCovisibilityGraphAndPairBackoffs) {
  test::TempDir dir("mapper_checkpoint_maintenance");
  const std::filesystem::path checkpoint_dir = dir.path() / "ckpt";
  MapperConfig config = checkpointConfig(dir.path() / "a", checkpoint_dir);
  config.checkpoint.period_s = 3600.0;  // the stop's checkpoint only
  config.pose_source = PoseSource::kTracker;
  config.creation.max_keyframes_per_subvolume = 2;
  config.maintenance.retry_after_s = 2.0;
  const auto& frames = roomFrames();
  std::vector<CovisibilityCandidate> edges;
  {
    Mapper first(config);
    RequestLog requests;
    first.setCovarianceRequester(requests.requester());
    std::string error;
    ASSERT_TRUE(first.start(&error)) << error;
    // Subvolumes 0 (keyframes 100, 101), 1 (102, 103) and 2 (104, active); 0 and 1 share 50.
    const std::vector<std::pair<KeyframeId, std::pair<uint64_t, uint64_t>>> keyframes = {
        {100, {0, 100}}, {101, {0, 100}}, {102, {50, 150}}, {103, {50, 150}}, {104, {90, 1100}}};
    for (const auto& [id, landmarks] : keyframes) {
      ASSERT_TRUE(first.onKeyframe(id, utimeOf(frames[0]), frames[0].T_G_C,
                                   landmarkRange(landmarks.first, landmarks.second)));
    }
    const std::optional<FusionCovarianceRequest> request = requests.waitFor(0);
    ASSERT_TRUE(request.has_value());
    ASSERT_EQ(request->pairs.size(), 1u);
    first.onCovarianceReply(request->request_id, {FusionCovarianceAnswer{true, "", 1.0}});
    ASSERT_TRUE(first.waitUntilIdle(kIdleTimeout));
    ASSERT_EQ(first.status().fusion.rejected_by_q, 1u);
    edges = first.covisibilityEdges();
    ASSERT_EQ(edges.size(), 3u);  // (0, 1) 50, (0, 2) 10, (1, 2) 60
    EXPECT_EQ(first.status().checkpoint_generation, 0u);
    first.stop();
    const MapperStatus s = first.status();
    EXPECT_EQ(s.checkpoint_generation, readManifest(checkpoint_dir.string(), nullptr)->generation);
    EXPECT_GT(s.last_checkpoint_utime, 0);
    const MapperReply status = runCommand(&first, "status");
    EXPECT_EQ(status.value("checkpoint_generation"), std::to_string(s.checkpoint_generation));
    EXPECT_EQ(status.value("checkpoint_dir"), checkpoint_dir.string());
    EXPECT_NE(status.value("last_checkpoint_age_s"), "-");
  }
  config.output_dir = (dir.path() / "b").string();
  Mapper resumed(config);
  RequestLog requests;
  resumed.setCovarianceRequester(requests.requester());
  const std::optional<MapperReply> reply = resumed.resumeFromCheckpoint();
  ASSERT_TRUE(reply && reply->ok) << (reply ? reply->message : "no reply");
  EXPECT_NE(reply->message.find("covisibility restored: 3 subvolumes with landmarks, 1 pair "
                                "back-offs"),
            std::string::npos)
      << reply->message;
  const std::vector<CovisibilityCandidate> resumed_edges = resumed.covisibilityEdges();
  ASSERT_EQ(resumed_edges.size(), edges.size());
  for (size_t i = 0; i < edges.size(); ++i) {
    EXPECT_EQ(resumed_edges[i].a, edges[i].a);
    EXPECT_EQ(resumed_edges[i].b, edges[i].b);
    EXPECT_EQ(resumed_edges[i].shared, edges[i].shared);
    EXPECT_EQ(resumed_edges[i].landmarks_a, edges[i].landmarks_a);
    EXPECT_EQ(resumed_edges[i].landmarks_b, edges[i].landmarks_b);
  }
  std::string error;
  ASSERT_TRUE(resumed.start(&error)) << error;
  // The rejected pair waits out the rest of its 2 s (counted from the load), then is asked.
  std::this_thread::sleep_for(milliseconds(500));
  {
    std::lock_guard<std::mutex> lock(requests.mutex);
    EXPECT_TRUE(requests.requests.empty());
  }
  const std::optional<FusionCovarianceRequest> again = requests.waitFor(0);
  ASSERT_TRUE(again.has_value());
  EXPECT_EQ(again->pairs[0].older, 0);
  EXPECT_EQ(again->pairs[0].newer, 1);
}

// Resume is skipped when off or on a first run; an unreadable checkpoint is refused with the
// file named (cblox-mapper exits 2); a failing checkpoint is counted, logged once per
// distinct message, and the mapper keeps mapping.
TEST(MapperTest, CheckpointResumeRefusalsAndFailures) {
  test::TempDir dir("mapper_checkpoint_bad");
  MapperConfig off = checkpointConfig(dir.path() / "a", dir.path() / "ckpt");
  off.checkpoint.resume = false;
  const std::string manifest = (dir.path() / "ckpt" / kManifestFileName).string();
  std::filesystem::create_directories(dir.path() / "ckpt");
  { std::ofstream(manifest) << "not a manifest"; }
  EXPECT_FALSE(Mapper(off).resumeFromCheckpoint());  // resume: false
  MapperConfig no_dir = testConfig(dir.path() / "a");
  EXPECT_FALSE(Mapper(no_dir).resumeFromCheckpoint());  // no checkpoint.dir

  Mapper corrupt(checkpointConfig(dir.path() / "a", dir.path() / "ckpt"));
  const std::optional<MapperReply> refused = corrupt.resumeFromCheckpoint();
  ASSERT_TRUE(refused);
  EXPECT_FALSE(refused->ok);
  EXPECT_NE(refused->message.find("cannot resume from checkpoint.dir"), std::string::npos)
      << refused->message;
  EXPECT_NE(refused->message.find(manifest), std::string::npos) << refused->message;
  EXPECT_EQ(corrupt.status().num_submaps, 0u);

  // The checkpoint directory is a regular file: every checkpoint fails the same way.
  const std::filesystem::path blocked = dir.path() / "blocked";
  { std::ofstream(blocked) << "x"; }
  LogLines log;
  Mapper failing(checkpointConfig(dir.path() / "b", blocked), log.sink());
  EXPECT_FALSE(failing.resumeFromCheckpoint());  // no manifest there
  std::string error;
  ASSERT_TRUE(failing.start(&error)) << error;
  feed(&failing, 0, 6);
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(30);
  while (failing.status().checkpoint_failures < 3 && std::chrono::steady_clock::now() < deadline) {
    std::this_thread::sleep_for(milliseconds(5));
  }
  EXPECT_GE(failing.status().checkpoint_failures, 3u);
  EXPECT_EQ(failing.status().checkpoints_written, 0u);
  EXPECT_EQ(log.countContaining("checkpoint into " + blocked.string() + " failed"), 1u);
  EXPECT_EQ(failing.status().frames_integrated, 6u);
}

TEST(MapperTest, PlanningExportsCheckTheirArgumentsAndFollowTheMap) {
  test::TempDir dir("mapper_planning");
  MapperConfig config = testConfig(dir.path());
  const auto command = [](const char* name, std::map<std::string, std::string> args) {
    MapperCommand c;
    c.id = 7;
    c.name = name;
    c.args = std::move(args);
    return c;
  };
  {
    config.planning.enabled = false;
    Mapper off(config);
    std::string error;
    ASSERT_TRUE(off.start(&error)) << error;
    const MapperReply r =
        runCommand(&off, command("export_distance_slice", {{"path", "s.png"}, {"z", "1"}}));
    EXPECT_FALSE(r.ok);
    EXPECT_NE(r.message.find("planning.enabled"), std::string::npos) << r.message;
    off.stop();
  }
  config.planning.enabled = true;
  Mapper mapper(config);
  std::string error;
  ASSERT_TRUE(mapper.start(&error)) << error;
  const int64_t epoch = mapper.mapEpoch();
  EXPECT_GT(epoch, 0);
  feed(&mapper, 0, 8);
  // The slice needs no sync: the command brings every field up to date first, the active
  // subvolume's too.
  const MapperReply slice =
      runCommand(&mapper, command("export_distance_slice", {{"path", "slice.png"}, {"z", "1.0"}}));
  ASSERT_TRUE(slice.ok) << slice.message;
  EXPECT_TRUE(std::filesystem::exists(dir.file("slice.png")));
  EXPECT_NE(slice.value("occupied"), "0");
  EXPECT_FALSE(mapper.trajectoryG().empty());
  const MapperReply grid = runCommand(
      &mapper,
      command("export_distance_grid",
              {{"path", "grid.ply"}, {"box", "-1,-1,0.5,1,1,1.5"}, {"resolution", "0.1"}}));
  ASSERT_TRUE(grid.ok) << grid.message;
  EXPECT_EQ(grid.value("cells"), "4000");
  // Bad arguments are refused with their name, and counted.
  const uint64_t invalid = mapper.status().problem(InputProblem::kCommandInvalid);
  for (const auto& [c, what] : std::vector<std::pair<MapperCommand, std::string>>{
           {command("export_distance_slice", {{"path", "s.png"}}), "'z'"},
           {command("export_distance_slice", {{"path", "s.png"}, {"z", "high"}}), "'z'"},
           {command("export_distance_slice", {{"path", "s.png"}, {"z", "nan"}}), "'z'"},
           {command("export_distance_grid", {{"path", "g.ply"}, {"box", "1,2,3"}}), "'box'"},
           {command("export_distance_grid",
                    {{"path", "g.ply"}, {"box", "0,0,0,1,1,1"}, {"resolution", "0"}}),
            "'resolution'"},
           {command("export_distance_grid", {{"path", "../g.ply"}, {"box", "0,0,0,1,1,1"}}), ""},
       }) {
    const MapperReply r = runCommand(&mapper, c);
    EXPECT_FALSE(r.ok) << c.name;
    EXPECT_NE(r.message.find(what), std::string::npos) << r.message;
  }
  // A box too large for one grid is refused by the worker, with the reason.
  const MapperReply huge = runCommand(
      &mapper,
      command("export_distance_grid",
              {{"path", "g.ply"}, {"box", "0,0,0,1000,1000,1000"}, {"resolution", "0.01"}}));
  EXPECT_FALSE(huge.ok);
  EXPECT_NE(huge.message.find("cells"), std::string::npos) << huge.message;
  EXPECT_EQ(mapper.status().problem(InputProblem::kCommandInvalid), invalid + 6);
  EXPECT_EQ(mapper.mapEpoch(), epoch);  // mapping does not change the epoch
  mapper.stop();
}

}  // namespace
}  // namespace cblox
