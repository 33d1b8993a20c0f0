// Publishes one sample message (test/test_support/lcm_samples.h) of every top-level cblox LCM
// type on the cblox channel that carries it (../shared/DESIGN.md), for the lcm-spy test
// (test/daemon/run_lcm_spy_test.sh). Nested types (pose_t, image_t, camera_calibration_t,
// covariance_pair_t) travel inside their parents.
//
// Usage: publish_lcm_samples --list
//          prints "CHANNEL TYPE" per line (the test's expected table) and exits 0
//        publish_lcm_samples LCM_URL [ROUNDS] [PERIOD_MS]
//          publishes the whole set ROUNDS times (default 1), PERIOD_MS apart (default 200):
//          a subscriber that starts late still gets every channel.
// Exit status 0, 1 when LCM cannot be set up or a publish fails, 2 on a usage error.

#include <lcm/lcm-cpp.hpp>

#include <chrono>
#include <cstdio>
#include <functional>
#include <limits>
#include <optional>
#include <string>
#include <thread>
#include <vector>

#include <CLI/CLI.hpp>

#include "daemon/common/cli.h"
#include "test/test_support/lcm_samples.h"

namespace {

struct Sample {
  const char* channel;
  const char* type;
  std::function<int(lcm::LCM&, const char*)> publish;
};

template <typename Msg>
Sample Make(const char* channel, const char* type, Msg (*make)()) {
  return {channel, type, [make](lcm::LCM& lcm, const char* ch) {
            const Msg msg = make();
            return lcm.publish(ch, &msg);
          }};
}

std::vector<Sample> Samples() {
  namespace t = cblox::test;
  return {
      Make("CBLOX_STEREO", "stereo_pair_t", &t::MakeStereoPair),
      Make("CBLOX_DEPTH", "depth_frame_t", &t::MakeDepthFrame),
      Make("CBLOX_GT_POSE", "pose_stamped_t", &t::MakePoseStamped),
      Make("CBLOX_FRAME_POSE", "frame_pose_t", &t::MakeFramePose),
      Make("CBLOX_KEYFRAME", "keyframe_t", &t::MakeKeyframe),
      Make("CBLOX_KEYFRAME_POSES", "keyframe_pose_batch_t", &t::MakeKeyframePoseBatch),
      Make("CBLOX_COV_REQUEST", "covariance_request_t", &t::MakeCovarianceRequest),
      Make("CBLOX_COV_REPLY", "covariance_reply_t", &t::MakeCovarianceReply),
      Make("CBLOX_CMD", "command_t", &t::MakeCommand),
      Make("CBLOX_CMD_REPLY", "command_reply_t", &t::MakeCommandReply),
      Make("CBLOX_MAP_STATUS", "map_status_t", &t::MakeMapStatus),
      Make("CBLOX_HEARTBEAT", "heartbeat_t", &t::MakeHeartbeat),
      Make("CBLOX_DISTANCE_REQUEST", "distance_request_t", &t::MakeDistanceRequest),
      Make("CBLOX_DISTANCE_REPLY", "distance_reply_t", &t::MakeDistanceReply),
      Make("CBLOX_LOCAL_GRID", "local_grid_t", &t::MakeLocalGrid),
      Make("CBLOX_MESH_UPDATE", "mesh_update_t", &t::MakeMeshUpdate),
      Make("CBLOX_SUBVOLUMES", "subvolume_list_t", &t::MakeSubvolumeList),
  };
}

}  // namespace

int main(int argc, char** argv) {
  bool list = false;
  std::string url;
  long rounds = 1;
  long period_ms = 200;
  CLI::App app{
      "publish_lcm_samples: publishes the sample message of every top-level cblox LCM type on\n"
      "its channel (for the lcm-spy test).",
      "publish_lcm_samples"};
  app.add_flag("--list", list, "print \"CHANNEL TYPE\" per line and exit");
  CLI::Option* url_option = app.add_option("url", url, "LCM URL")->type_name("LCM_URL");
  app.add_option("rounds", rounds, "times the whole set is published")
      ->check(CLI::Range(1L, std::numeric_limits<long>::max()))
      ->capture_default_str();
  app.add_option("period_ms", period_ms, "milliseconds between rounds")
      ->check(CLI::Range(0L, std::numeric_limits<long>::max()))
      ->capture_default_str();
  if (const std::optional<int> code = cblox::parseCommandLine(app, argc, argv)) return *code;
  if (list == (url_option->count() > 0)) {
    std::fprintf(stderr, "publish_lcm_samples: give --list or an LCM URL (see --help)\n");
    return 2;
  }
  const std::vector<Sample> samples = Samples();
  if (list) {
    for (const Sample& s : samples) std::printf("%s %s\n", s.channel, s.type);
    return 0;
  }

  lcm::LCM lcm(url);
  if (!lcm.good()) {
    std::fprintf(stderr, "publish_lcm_samples: cannot set up LCM on %s\n", url.c_str());
    return 1;
  }
  for (long round = 0; round < rounds; ++round) {
    if (round > 0) std::this_thread::sleep_for(std::chrono::milliseconds(period_ms));
    for (const Sample& s : samples) {
      if (s.publish(lcm, s.channel) != 0) {
        std::fprintf(stderr, "publish_lcm_samples: publishing on %s failed\n", s.channel);
        return 1;
      }
    }
  }
  return 0;
}
