// cblox-tracker: the sparse stereo / RGB-D SLAM process. Tracks every frame, builds the
// sparse map (keyframes, landmarks, local BA, loop closure, global BA) and publishes the
// poses the dense mapper hangs its subvolumes on.
//
//   cblox-tracker --config config/tracker.yaml          # stereo, calibration from the messages
//   cblox-tracker --initial-pose-from-gt                 # simulator: G = the simulator's frame
//   cblox-tracker --calibration config/calibration/sim_rig.yaml     # camera from a file
//   cblox-tracker --mode rgbd                            # depth + registered colour
//   cblox-tracker --checkpoint-dir /var/lib/cblox/checkpoint/tracker   # save and resume
//
// Subscribes: stereo mode CBLOX_STEREO (stereo_pair_t), RGB-D mode CBLOX_DEPTH
// (depth_frame_t with registered colour); initial_pose ground_truth: CBLOX_GT_POSE
// (pose_stamped_t); CBLOX_COV_REQUEST (covariance_request_t) from the mapper.
// Publishes: CBLOX_FRAME_POSE (frame_pose_t) for every frame processed, CBLOX_KEYFRAME
// (keyframe_t) for every new keyframe, CBLOX_KEYFRAME_POSES (keyframe_pose_batch_t) after
// every local BA, loop correction and global BA, CBLOX_HEARTBEAT (heartbeat_t) every second
// (with input_silence_s: input_silent / input_age_ms, and the state says which input is silent),
// CBLOX_COV_REPLY (covariance_reply_t) for every request (computed on the covariance
// service's own low-priority thread).
// Frame poses are of the tracked camera (the rectified left camera, or the RGB-D camera).
// checkpoint.dir: the sparse map is checkpointed there (every checkpoint.period_s and at a
// clean stop) and, with checkpoint.resume, continued at start: the tracker relocalizes in it
// (README "Tracker map format"); a checkpoint that cannot be read is a configuration error.
// Exit status: 0 stopped by SIGINT/SIGTERM, 1 runtime error, 2 usage or configuration error.

#include <chrono>
#include <cstdio>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include <lcm/lcm-cpp.hpp>

#include "core/vocabulary/binary_vocabulary.h"
#include "daemon/common/daemon_options.h"
#include "daemon/common/input_watch.h"
#include "daemon/common/run_loop.h"
#include "daemon/common/yaml_config.h"
#include "daemon/tracker/tracker_config.h"
#include "daemon/tracker/tracker_lcm_node.h"
#include "daemon/tracker/tracker_node.h"
#include "daemon/tracker/tracker_options.h"
#include "daemon/tracker/tracker_vocabulary.h"

namespace cblox {
namespace {

using Clock = std::chrono::steady_clock;

struct Args {
  DaemonOptions daemon;
  TrackerOptions tracker;
  std::optional<std::string> checkpoint_dir;  ///< --checkpoint-dir DIR over checkpoint.dir
};

TrackerProcessConfig buildConfig(const Args& args) {
  TrackerProcessConfig config =
      loadDaemonConfig<TrackerProcessConfig>(args.daemon, loadTrackerConfig);
  if (args.checkpoint_dir) config.tracker.checkpoint.dir = *args.checkpoint_dir;
  applyTrackerOptions(args.tracker, &config);
  return config;
}

int run(const Args& args) {
  installStopHandlers();  // before the vocabulary loads: a stop then still exits 0
  const TrackerProcessConfig config = buildConfig(args);
  const TrackerNodeConfig& t = config.tracker;
  const std::unique_ptr<BinaryVocabulary> vocabulary = loadTrackerVocabulary(config.vocabulary);

  lcm::LCM lcm(config.lcm_url);
  if (!lcm.good()) {
    std::fprintf(stderr, "cblox-tracker: cannot open LCM (url '%s')\n", config.lcm_url.c_str());
    return 1;
  }
  // Input-silence health: the frame channel of the mode (heartbeat counters and state).
  const std::string& frame_channel =
      t.mode == TrackerMode::kStereo ? config.stereo_channel : config.depth_channel;
  InputWatch input_watch("cblox-tracker", config.input_silence_s);
  input_watch.watch(frame_channel);
  TrackerLcmNode lcm_node(config, &lcm);
  lcm_node.messageGuard().setInputWatch(&input_watch);
  TrackerNode node(t, vocabulary.get(), lcm_node.outputs());
  if (!args.daemon.quiet) {
    std::printf(
        "tracker: %s mode on %s, calibration from %s, initial pose %s, %d ORB features, "
        "vocabulary %s, loop closing %s\n",
        trackerModeName(t.mode), frame_channel.c_str(),
        config.calibration_source == CalibrationSource::kFile ? config.calibration_file.c_str()
                                                              : "the messages",
        initialPoseName(t.initial_pose), t.slam.frames.orb.num_features,
        vocabulary
            ? trackerVocabularyPath(config.vocabulary).c_str()
            : "none",
        vocabulary && t.slam.loop_closing_enabled ? "on" : "off");
    std::fflush(stdout);
  }
  if (!t.checkpoint.dir.empty() && t.checkpoint.resume) {
    // An unreadable checkpoint stops the start (repair or move it, or set checkpoint.resume:
    // false): silently starting a new map would orphan the mapper's subvolumes.
    std::string error;
    std::optional<TrackerResume> resume = loadTrackerResume(t.checkpoint.dir, &error);
    if (!error.empty()) throw ConfigError("checkpoint: cannot resume: " + error);
    if (resume) node.resumeFrom(std::move(*resume));
  }
  lcm_node.subscribe(&node);
  node.start();

  const Clock::time_point start = Clock::now();
  uint64_t last_processed = 0;
  Clock::time_point last_progress = start;
  auto progress = [&](const TrackerStatus& s, const char* prefix) {
    const double dt = std::chrono::duration<double>(Clock::now() - last_progress).count();
    const double rate = dt > 0 ? static_cast<double>(s.frames_processed - last_processed) / dt : 0;
    last_processed = s.frames_processed;
    last_progress = Clock::now();
    std::printf(
        "tracker: %s%llu frames (%.1f/s): %llu tracked, %llu lost, %llu relocalized, %llu "
        "dropped, %llu rejected; %llu keyframes, %llu landmarks, %llu loops; tracking median "
        "%.1f ms, frame median %.1f ms p95 %.1f ms; %llu checkpoints; %s\n",
        prefix, static_cast<unsigned long long>(s.frames_processed), rate,
        static_cast<unsigned long long>(s.frames_tracked),
        static_cast<unsigned long long>(s.frames_lost),
        static_cast<unsigned long long>(s.relocalizations),
        static_cast<unsigned long long>(s.frames_dropped),
        static_cast<unsigned long long>(s.frames_rejected),
        static_cast<unsigned long long>(s.keyframes), static_cast<unsigned long long>(s.landmarks),
        static_cast<unsigned long long>(s.loops_closed), s.tracking_ms_median, s.frame_ms_median,
        s.frame_ms_p95, static_cast<unsigned long long>(s.checkpoints_written), s.state.c_str());
    std::fflush(stdout);
  };

  SystemdNotifier notifier;
  std::vector<PeriodicTask> tasks{{config.status_period_s, 0.0, [&] {
                                     const TrackerStatus s = node.status();
                                     lcm_node.publishHeartbeat(s, s.state);
                                     notifier.status(std::to_string(s.frames_processed) +
                                                     " frames, " + std::to_string(s.keyframes) +
                                                     " keyframes; " + s.state);
                                   }}};
  if (!args.daemon.quiet) {
    tasks.push_back(
        {config.progress_period_s, config.progress_period_s, [&] { progress(node.status(), ""); }});
  }
  const int exit_code = serveUntilStopped(lcm, "cblox-tracker", tasks, &notifier);
  input_watch.stopWatching();  // the last heartbeat says "stopped", not "input silent"
  node.stop();  // finishes the frame in hand, then stops local mapping and loop closing
  const TrackerStatus s = node.status();
  lcm_node.publishHeartbeat(s, "stopped");
  if (!args.daemon.quiet) progress(s, "stopped: ");
  return exit_code;
}

}  // namespace
}  // namespace cblox

int main(int argc, char** argv) {
  cblox::Args args;
  CLI::App app{
      "cblox-tracker: the sparse stereo / RGB-D SLAM process: tracks the frames of CBLOX_STEREO\n"
      "(or CBLOX_DEPTH in rgbd mode) and publishes poses, keyframes and keyframe pose updates.\n"
      "Runs until SIGINT/SIGTERM.\n"
      "Exit status: 0 stopped by signal, 1 runtime error, 2 usage/configuration error.",
      "cblox-tracker"};
  cblox::addDaemonOptions(app, &args.daemon, "config/tracker.yaml");
  cblox::addTrackerOptions(app, &args.tracker);
  app.add_option("--checkpoint-dir", args.checkpoint_dir,
                 "checkpoint directory of the sparse map (over checkpoint.dir; the systemd\n"
                 "unit gives /var/lib/cblox/checkpoint/tracker)")
      ->type_name("DIR");
  if (const std::optional<int> code = cblox::parseCommandLine(app, argc, argv)) return *code;
  return cblox::runProcess("cblox-tracker", [&] { return cblox::run(args); });
}
