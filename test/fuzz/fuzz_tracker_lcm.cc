// Fuzz target: cblox-tracker's LCM side (TrackerLcmNode, daemon/tracker/tracker_lcm_node.h)
// with a running TrackerNode (tracking, local mapping; no vocabulary), over the in-process
// bus (memq_bus.h). The first byte of the input chooses the tracker (stereo with an identity
// initial pose, or RGB-D waiting for ground-truth poses: their subscriptions differ) and the
// channel; the rest is published there and handled as cblox-tracker handles a message:
// message guard, frame decoding and checks, then the SLAM on the frame; the target waits
// until the node is settled. Both trackers live for the whole run.

#include <chrono>
#include <cstddef>
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "daemon/tracker/tracker_config.h"
#include "daemon/tracker/tracker_lcm_node.h"
#include "daemon/tracker/tracker_node.h"
#include "test/fuzz/support/fuzz_check.h"
#include "test/fuzz/support/memq_bus.h"

namespace cblox {
namespace {

// One cblox-tracker: config, bus, node, LCM node.
struct TrackerUnderTest {
  TrackerProcessConfig config;
  fuzz::MemqBus bus;
  std::unique_ptr<TrackerLcmNode> lcm_node;
  std::unique_ptr<TrackerNode> node;
  std::vector<std::string> channels;

  TrackerUnderTest(TrackerMode mode, InitialPose initial_pose) {
    config.tracker.mode = mode;
    config.tracker.initial_pose = initial_pose;
    config.tracker.log_interval_s = 3600.0;
    // A frame before the map starts looks for its ground-truth pose once instead of waiting up
    // to 1 s for it: a pose an earlier input delivered is still found, and the run is not
    // spent asleep (the wait held the target at 60-90 executions per second).
    config.tracker.ground_truth_wait_s = 0.0;
    lcm_node = std::make_unique<TrackerLcmNode>(config, bus.lcm());
    node = std::make_unique<TrackerNode>(config.tracker, nullptr, lcm_node->outputs());
    lcm_node->subscribe(node.get());
    node->start();
    channels = {mode == TrackerMode::kStereo ? config.stereo_channel : config.depth_channel,
                config.covariance_request_channel, config.heartbeat_channel};
    if (initial_pose == InitialPose::kGroundTruth) channels.push_back(config.ground_truth_channel);
  }
};

TrackerUnderTest& trackerUnderTest(bool rgbd) {
  static TrackerUnderTest stereo(TrackerMode::kStereo, InitialPose::kIdentity);
  static TrackerUnderTest rgbd_gt(TrackerMode::kRgbd, InitialPose::kGroundTruth);
  return rgbd ? rgbd_gt : stereo;
}

}  // namespace
}  // namespace cblox

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  if (size == 0) return 0;
  cblox::TrackerUnderTest& t = cblox::trackerUnderTest(data[0] & 0x80);
  const std::string& channel = t.channels[(data[0] & 0x7f) % t.channels.size()];
  t.bus.deliver(channel, data + 1, size - 1);
  FUZZ_CHECK(t.node->waitUntilSettled(std::chrono::seconds(60)), "the tracker did not settle");
  t.bus.drain();  // its outputs (poses, keyframes, covariance replies)
  return 0;
}
