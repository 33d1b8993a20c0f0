// The map's memory cap (core/mapping/memory_cap.h): the stage decision, the two steps that
// enforce it on a frame, and the whole policy in a Mapper on the analytic room with a tiny
// cap (the cap holds, near blocks are still integrated, far blocks are not allocated, and
// the counters say what happened).

#include "core/mapping/memory_cap.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <vector>

#include <gtest/gtest.h>

#include "core/mapping/mapper.h"
#include "drivers/synthetic/scenes.h"
#include "drivers/synthetic/synthetic_frame_source.h"
#include "test/test_support/temp_dir.h"

namespace cblox {
namespace {

constexpr size_t kMiB = size_t{1024} * 1024;

TEST(MemoryCapStateTest, FollowsTheMapBytesThroughTheStages) {
  MemoryCapConfig config;
  config.cap_mb = 10;
  config.near_only_fraction = 0.5;
  EXPECT_EQ(memoryCapState(config, 0), MemoryCapState::kBelow);
  EXPECT_EQ(memoryCapState(config, 5 * kMiB - 1), MemoryCapState::kBelow);
  EXPECT_EQ(memoryCapState(config, 5 * kMiB), MemoryCapState::kNearOnly);
  EXPECT_EQ(memoryCapState(config, 10 * kMiB - 1), MemoryCapState::kNearOnly);
  EXPECT_EQ(memoryCapState(config, 10 * kMiB), MemoryCapState::kFull);
  EXPECT_EQ(memoryCapState(config, 100 * kMiB), MemoryCapState::kFull);
  config.cap_mb = 0;
  EXPECT_EQ(memoryCapState(config, 100 * kMiB), MemoryCapState::kOff);
  EXPECT_STREQ(memoryCapStateName(MemoryCapState::kNearOnly), "near_only");
  EXPECT_STREQ(memoryCapStateName(MemoryCapState::kFull), "full");
}

TEST(MemoryCapStateTest, ValidateNamesTheField) {
  MemoryCapConfig config;
  EXPECT_TRUE(config.validate().empty());
  config.near_only_fraction = 0.0;
  EXPECT_NE(config.validate().find("near_only_fraction"), std::string::npos);
  config.near_only_fraction = 1.0;
  config.near_distance_m = -1.0f;
  EXPECT_NE(config.validate().find("near_distance_m"), std::string::npos);
}

TEST(MemoryCapStepsTest, CutDepthBeyondZeroesOnlyFarReadings) {
  DepthImage depth(4, 1);
  depth.data = {0.5f, 2.0f, 2.5f, 0.0f};
  EXPECT_EQ(cutDepthBeyond(&depth, 2.0f), 1u);
  EXPECT_EQ(depth.data, (std::vector<float>{0.5f, 2.0f, 0.0f, 0.0f}));
}

TEST(MemoryCapStepsTest, CutDepthOutsideBlocksKeepsOnlyPointsInAllocatedBlocks) {
  TsdfLayer layer(LayerConfig{0.04f, 8});  // 32 cm blocks
  // The camera 1 m along -z of the origin looks along +z: at depth 1 m pixel (1, 0) sees
  // (0.05, -0.1, 0) in M, pixel (0, 0) sees (-0.05, -0.1, 0), pixel (1, 1) (0.05, 0, 0).
  const PinholeIntrinsics K{10.0, 10.0, 0.5, 1.0, 2, 2};
  const Transformation T_M_D(Eigen::Quaternionf::Identity(), Eigen::Vector3f(0, 0, -1));
  layer.allocateBlock(BlockIndex(0, -1, 0));  // holds (0.05, -0.1, 0)
  DepthImage depth(2, 2);
  depth.data = {1.0f, 1.0f, 0.0f, 1.0f};  // (0,0) -> x < 0: no block; (1,1) -> y = 0: none
  EXPECT_EQ(cutDepthOutsideBlocks(&depth, K, T_M_D, layer), 2u);
  EXPECT_EQ(depth.data, (std::vector<float>{0.0f, 1.0f, 0.0f, 0.0f}));
}

TEST(MemoryCapStepsTest, NewBlockRefusalRemovesOnlyTheBlocksAddedSinceRemember) {
  TsdfLayer layer(LayerConfig{0.04f, 8});
  layer.allocateBlock(BlockIndex(0, 0, 0))->voxel(0).weight = 3.0f;
  layer.allocateBlock(BlockIndex(1, 0, 0));
  NewBlockRefusal refusal;
  refusal.remember(layer);
  EXPECT_EQ(refusal.removeNewBlocks(&layer), 0u);  // nothing added
  layer.allocateBlock(BlockIndex(0, 0, 0));        // existing: not new
  layer.allocateBlock(BlockIndex(5, 0, 0));
  layer.allocateBlock(BlockIndex(0, 7, 0));
  EXPECT_EQ(refusal.removeNewBlocks(&layer), 2u);
  EXPECT_EQ(layer.numBlocks(), 2u);
  ASSERT_NE(layer.getBlock(BlockIndex(0, 0, 0)), nullptr);
  EXPECT_EQ(layer.getBlock(BlockIndex(0, 0, 0))->voxel(0).weight, 3.0f);
  EXPECT_NE(layer.getBlock(BlockIndex(1, 0, 0)), nullptr);
  EXPECT_EQ(layer.getBlock(BlockIndex(5, 0, 0)), nullptr);
}

// --- The policy in a Mapper ------------------------------------------------------------------

PinholeIntrinsics smallCamera() { return {120.0, 120.0, 79.5, 59.5, 160, 120}; }

const std::vector<SyntheticFrame>& roomFrames() {
  static const std::vector<SyntheticFrame> frames = [] {
    SyntheticDepthSource source(
        makeDemoRoom(), smallCamera(),
        makeOrbitTrajectory(Eigen::Vector3d(0, 0, 0), 1.5, 1.4, 24, Eigen::Vector3d(0, 0, 1.0)),
        10.0, 6.0);
    std::vector<SyntheticFrame> f(source.size());
    for (SyntheticFrame& frame : f) source.next(&frame);
    return f;
  }();
  return frames;
}

// One subvolume for the whole sequence (its frame is the first frame's pose).
MapperConfig capConfig(const std::filesystem::path& dir, const MemoryCapConfig& cap) {
  MapperConfig config;
  config.layer = LayerConfig{0.04f, 8};
  config.output_dir = dir.string();
  config.keyframe_every_n_frames = 1000;
  // Every frame whole: a time budget cuts frames short on a loaded machine, and the map's
  // growth per frame, which the test compares between two runs, would depend on the load.
  config.integrator.max_integration_time_s = 0.0;
  config.worker_sched_idle = false;
  config.worker_niceness = 0;
  config.memory_cap = cap;
  config.planning.enabled = true;  // the cap counts the distance fields too
  return config;
}

struct Fed {
  std::vector<size_t> bytes;   // map bytes after each frame
  std::vector<size_t> blocks;  // map blocks after each frame
  std::vector<MemoryCapState> states;
};

// Feeds frames [0, n) one at a time (no drops) and records the map after each.
Fed feed(Mapper* mapper, size_t n) {
  Fed fed;
  const auto& frames = roomFrames();
  for (size_t i = 0; i < n; ++i) {
    DepthFrame depth;
    depth.utime = frames[i].timestamp_ns / 1000;
    depth.frame_id = static_cast<int64_t>(i);
    depth.depth = frames[i].depth;
    depth.color = frames[i].color;
    depth.intrinsics = smallCamera();
    EXPECT_TRUE(mapper->onDepthFrame(std::move(depth)));
    TimedPose pose;
    pose.utime = frames[i].timestamp_ns / 1000;
    pose.T_G_C = frames[i].T_G_C;
    EXPECT_TRUE(mapper->onFramePose(pose));
    EXPECT_TRUE(mapper->waitUntilIdle(std::chrono::milliseconds(10000)));
    // The distance fields follow each frame here (in a running mapper, within
    // planning.refresh_period_s), so the map's bytes after a frame include them.
    EXPECT_TRUE(mapper->syncPlanningMap(std::chrono::milliseconds(60000)));
    const MapperStatus s = mapper->status();
    fed.bytes.push_back(s.memory_bytes);
    fed.blocks.push_back(s.num_blocks);
    fed.states.push_back(s.memory_cap.state);
  }
  return fed;
}

// Summed voxel weight of the active subvolume.
double activeWeight(const Mapper& mapper) {
  const std::shared_ptr<Submap> active = mapper.collection().activeSubmap();
  if (!active) return 0.0;
  const auto lock = active->lockLayer();
  double sum = 0.0;
  for (const auto& [key, block] : active->layer().blocks()) {
    for (int v = 0; v < block->numVoxels(); ++v) sum += block->voxel(v).weight;
  }
  return sum;
}

// The largest distance from a block centre of the map to the nearest camera position of
// frames [0, n).
double farthestBlock(const Mapper& mapper, size_t n) {
  double farthest = 0.0;
  for (const std::shared_ptr<Submap>& submap : mapper.collection().submaps()) {
    const auto lock = submap->lockLayer();
    const Transformationd T_G_M = submap->T_G_M();
    const TsdfLayer& layer = submap->layer();
    for (const auto& [key, block] : layer.blocks()) {
      const Eigen::Vector3d c_M =
          (block->origin() + Eigen::Vector3f::Constant(0.5f * layer.blockSize())).cast<double>();
      const Eigen::Vector3d c_G = T_G_M * c_M;
      double nearest = 1e9;
      for (size_t i = 0; i < n; ++i) {
        nearest = std::min(nearest, (roomFrames()[i].T_G_C.translation() - c_G).norm());
      }
      farthest = std::max(farthest, nearest);
    }
  }
  return farthest;
}

TEST(MemoryCapMapperTest, ATinyCapHoldsAndNearBlocksAreStillIntegrated) {
  constexpr size_t kFrames = 24;
  test::TempDir dir("memory_cap");
  // Uncapped: how big the map gets, and the largest growth of one frame.
  MemoryCapConfig off;
  off.cap_mb = 0;
  Mapper free_mapper(capConfig(dir.path() / "off", off), [](const std::string&) {});
  std::string error;
  ASSERT_TRUE(free_mapper.start(&error)) << error;
  const Fed free_run = feed(&free_mapper, kFrames);
  // (The first frame sees most of the room: the cap is set above it.)
  size_t max_growth = 0;
  for (size_t i = 1; i < kFrames; ++i) {
    max_growth = std::max(max_growth,
                          free_run.bytes[i] - std::min(free_run.bytes[i], free_run.bytes[i - 1]));
  }
  EXPECT_EQ(free_mapper.status().memory_cap.state, MemoryCapState::kOff);
  EXPECT_EQ(free_mapper.status().memory_cap.frames_near_only, 0u);
  // The cap: subvolumes, their distance fields and the waves' working memory; the first
  // frame is at 85 % of it, below the near-only stage.
  const size_t cap_mb = (free_run.bytes.front() * 100 / 85 + kMiB - 1) / kMiB;
  const size_t cap_bytes = cap_mb * kMiB;
  ASSERT_GT(free_run.bytes.back(), cap_bytes + 2 * max_growth) << "the scene must overflow";

  MemoryCapConfig cap;
  cap.cap_mb = cap_mb;
  cap.near_only_fraction = 0.9;
  cap.near_distance_m = 2.5f;
  Mapper mapper(capConfig(dir.path() / "cap", cap), [](const std::string&) {});
  ASSERT_TRUE(mapper.start(&error)) << error;
  const Fed run = feed(&mapper, kFrames - 2);

  // The cap holds: at most one frame's growth above it, and once full, no block is added.
  const size_t first_full = static_cast<size_t>(
      std::find(run.states.begin(), run.states.end(), MemoryCapState::kFull) - run.states.begin());
  ASSERT_LT(first_full, run.states.size()) << "the cap never engaged";
  for (size_t i = 0; i < run.bytes.size(); ++i) {
    EXPECT_LE(run.bytes[i], cap_bytes + max_growth) << "frame " << i;
    if (i > first_full) {
      EXPECT_LE(run.blocks[i], run.blocks[i - 1]) << "frame " << i;
    }
  }
  // The stages came in order: below, near-only, full.
  EXPECT_EQ(run.states.front(), MemoryCapState::kBelow);
  EXPECT_NE(std::find(run.states.begin(), run.states.end(), MemoryCapState::kNearOnly),
            run.states.end());
  EXPECT_TRUE(std::is_sorted(run.states.begin(), run.states.end()));

  // At the cap, near blocks are still integrated: the next frame adds weight, no block.
  const double weight_before = activeWeight(mapper);
  const size_t blocks_before = mapper.status().num_blocks;
  {
    const auto& frames = roomFrames();
    const size_t i = kFrames - 2;
    DepthFrame depth;
    depth.utime = frames[i].timestamp_ns / 1000;
    depth.frame_id = static_cast<int64_t>(i);
    depth.depth = frames[i].depth;
    depth.intrinsics = smallCamera();
    ASSERT_TRUE(mapper.onDepthFrame(std::move(depth)));
    TimedPose pose;
    pose.utime = frames[i].timestamp_ns / 1000;
    pose.T_G_C = frames[i].T_G_C;
    ASSERT_TRUE(mapper.onFramePose(pose));
    ASSERT_TRUE(mapper.waitUntilIdle(std::chrono::milliseconds(10000)));
  }
  EXPECT_GT(activeWeight(mapper), weight_before);
  EXPECT_EQ(mapper.status().num_blocks, blocks_before);

  // The counters say what happened.
  const MapperStatus s = mapper.status();
  EXPECT_EQ(s.memory_cap.state, MemoryCapState::kFull);
  EXPECT_EQ(s.memory_cap_bytes, cap_bytes);
  EXPECT_EQ(s.memory_cap.frames_at_cap, kFrames - 1 - first_full);
  EXPECT_GT(s.memory_cap.blocks_refused, 0u);
  EXPECT_GE(s.memory_cap.frames_near_only, s.memory_cap.frames_at_cap + 1);
  EXPECT_EQ(s.frames_integrated, kFrames - 1);
  const std::map<std::string, int64_t> counters = mapper.statusCounters();
  EXPECT_EQ(counters.at("blocks_refused"), static_cast<int64_t>(s.memory_cap.blocks_refused));
  EXPECT_EQ(counters.at("frames_at_memory_cap"), static_cast<int64_t>(s.memory_cap.frames_at_cap));
}

TEST(MemoryCapMapperTest, NearOnlyAllocatesNoFarBlock) {
  constexpr size_t kFrames = 12;
  test::TempDir dir("memory_cap_near");
  constexpr float kNear = 1.0f;
  MemoryCapConfig off;
  off.cap_mb = 0;
  Mapper free_mapper(capConfig(dir.path() / "off", off), [](const std::string&) {});
  std::string error;
  ASSERT_TRUE(free_mapper.start(&error)) << error;
  feed(&free_mapper, kFrames);

  MemoryCapConfig near;  // near-only from the first byte on, never full
  near.cap_mb = 1024;
  near.near_only_fraction = 1e-9;
  near.near_distance_m = kNear;
  Mapper mapper(capConfig(dir.path() / "near", near), [](const std::string&) {});
  ASSERT_TRUE(mapper.start(&error)) << error;
  const Fed run = feed(&mapper, kFrames);
  ASSERT_EQ(run.states.back(), MemoryCapState::kNearOnly);

  // A block is allocated when it is within truncation of a measured point: measured depth
  // <= kNear puts its centre within kNear / cos(half the field of view) + truncation + half
  // a block diagonal of the camera.
  const double half_fov = std::atan(std::hypot(80.0, 60.0) / 120.0);
  const double bound = kNear / std::cos(half_fov) + 0.12 + 0.5 * std::sqrt(3.0) * 0.32;
  EXPECT_GT(farthestBlock(free_mapper, kFrames), bound) << "the scene must have far surfaces";
  EXPECT_LE(farthestBlock(mapper, kFrames), bound);
  EXPECT_GT(mapper.status().num_blocks, 0u);
  // Every frame: the first one's new subvolume already counts (its empty layer's bytes).
  EXPECT_EQ(mapper.status().memory_cap.frames_near_only, kFrames);
  EXPECT_EQ(mapper.status().memory_cap.frames_at_cap, 0u);
}

}  // namespace
}  // namespace cblox
