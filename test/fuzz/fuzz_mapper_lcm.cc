// Fuzz target: cblox-mapper's LCM side (MapperNode, daemon/mapper/mapper_lcm_node.h) with a
// running Mapper, over the in-process bus (memq_bus.h). The first byte of the input chooses
// the pose source (ground truth or tracker: their subscriptions differ; the tracker-mode mapper
// also keeps distance fields and publishes local grids) and the channel; the
// rest is published there and handled as cblox-mapper handles a message: message guard,
// conversion, Mapper call (integration, maintenance, commands), then the target waits until
// the mapper is idle. The two mappers live for the whole run, so inputs build on each other.

#include <chrono>
#include <cstddef>
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "core/mapping/mapper.h"
#include "daemon/mapper/mapper_lcm_node.h"
#include "daemon/mapper/mapper_process_config.h"
#include "test/fuzz/support/fuzz_check.h"
#include "test/fuzz/support/fuzz_files.h"
#include "test/fuzz/support/memq_bus.h"

namespace cblox {
namespace {

// One cblox-mapper: config, bus, Mapper, node.
struct MapperUnderTest {
  MapperProcessConfig config;
  fuzz::MemqBus bus;
  std::unique_ptr<Mapper> mapper;
  std::unique_ptr<MapperNode> node;
  std::vector<std::string> channels;

  MapperUnderTest(PoseSource pose_source, const std::string& output_dir) {
    config.mapper.pose_source = pose_source;
    config.mapper.output_dir = output_dir;
    config.mapper.max_pose_wait_s = 0.0;  // a frame without its pose is refused at once
    // Revisit anchoring on (off by default): frame poses name reference keyframes, and hostile
    // ones must not start subvolumes anywhere they should not.
    config.mapper.creation.revisit_after_frames = 2;
    config.mapper.creation.revisit_max_frames = 3;
    // A small memory cap (about 120 blocks): the map these mappers build over a whole run
    // stays small, and its stages (near-only, full) are reached by hostile frames too. Without
    // it the map grew over the run and each export_mesh command, which fuses every subvolume
    // (5-15 us per voxel sample under the sanitizers), took minutes late in a run; at 4 MiB
    // exports still held the target at about 100 executions per second.
    config.mapper.memory_cap.cap_mb = 1;
    // The planner interface on the tracker-mode mapper (fields, queries, local grids); the
    // other keeps it off (requests answered NO_PLANNING_MAP).
    config.mapper.planning.enabled = pose_source == PoseSource::kTracker;
    if (pose_source == PoseSource::kTracker) {
      config.mapper.planning.refresh_period_s = 0.05;
      config.mapper.planning.service.grid_period_s = 0.05;
      config.mapper.planning.service.grid_size_m = Eigen::Vector3d(2.0, 2.0, 1.0);
      config.mapper.planning.service.grid_resolution_m = 0.1;
    }
    mapper = std::make_unique<Mapper>(config.mapper, [](const std::string&) {});
    std::string error;
    FUZZ_CHECK(mapper->start(&error), error);
    node = std::make_unique<MapperNode>(config, bus.lcm(), mapper.get());
    node->subscribe();
    channels = {config.depth_channel, config.keyframe_poses_channel, config.command_channel,
                config.heartbeat_channel};
    if (pose_source == PoseSource::kGroundTruth) {
      channels.push_back(config.ground_truth_channel);
    } else {
      channels.insert(channels.end(), {config.frame_pose_channel, config.keyframe_channel,
                                       config.covariance_reply_channel});
    }
    channels.push_back(config.distance_request_channel);  // last: the seeds' indices hold
  }
};

MapperUnderTest& mapperUnderTest(bool tracker_mode) {
  static const std::string dir = fuzz::freshScratchDir();  // not emptied again in this target
  static MapperUnderTest ground_truth(PoseSource::kGroundTruth, dir + "/gt");
  static MapperUnderTest tracker(PoseSource::kTracker, dir + "/tracker");
  return tracker_mode ? tracker : ground_truth;
}

}  // namespace
}  // namespace cblox

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  if (size == 0) return 0;
  cblox::MapperUnderTest& m = cblox::mapperUnderTest(data[0] & 0x80);
  const std::string& channel = m.channels[(data[0] & 0x7f) % m.channels.size()];
  m.bus.deliver(channel, data + 1, size - 1);
  FUZZ_CHECK(m.mapper->waitUntilIdle(std::chrono::seconds(60)), "the mapper did not become idle");
  m.bus.drain();  // replies and requests it published meanwhile
  return 0;
}
