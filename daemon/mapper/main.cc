// cblox-mapper: the dense mapper process. Integrates depth frames into a collection of TSDF
// subvolumes, moves subvolumes when keyframe poses are corrected, and exports meshes on
// command.
//
//   cblox-mapper --config config/mapper.yaml                       # ground-truth poses
//   cblox-mapper --pose-source tracker --output-dir /data/maps
//   cblox-mapper --config config/mapper.yaml --load-map /data/maps/run1   # continue a saved map
//   cblox-mapper --checkpoint-dir /var/lib/cblox/checkpoint/mapper       # checkpoints + resume
//
// Subscribes: CBLOX_DEPTH (depth_frame_t); ground_truth mode: CBLOX_GT_POSE
// (pose_stamped_t); tracker mode: CBLOX_FRAME_POSE (frame_pose_t), CBLOX_KEYFRAME
// (keyframe_t), CBLOX_COV_REPLY (covariance_reply_t); both: CBLOX_KEYFRAME_POSES
// (keyframe_pose_batch_t), CBLOX_CMD (command_t).
// Publishes: CBLOX_MAP_STATUS (map_status_t) and CBLOX_HEARTBEAT (heartbeat_t) every second
// (with input_silence_s: input_silent / input_age_ms for depth and poses, in the state too),
// CBLOX_CMD_REPLY (command_reply_t); with mesh_stream.enabled, CBLOX_SUBVOLUMES
// (subvolume_list_t) and CBLOX_MESH_UPDATE (mesh_update_t) every mesh_stream.period_s; tracker mode: CBLOX_COV_REQUEST (covariance_request_t)
// for the map maintenance's fusion candidates.
// Poses on CBLOX_GT_POSE / CBLOX_FRAME_POSE are of the body (primary camera) frame B; a depth
// frame's camera is placed at T_G_B * calibration.T_B_C.
// --load-map DIR loads a saved map (cblox-ctl save-map) before the mapper serves; a map that
// cannot be loaded (missing, corrupt, other voxel size) is a configuration error. Without it,
// checkpoint.resume loads the last periodic checkpoint of checkpoint.dir the same way (none
// there: a first run, the map starts empty; unreadable: a configuration error).
// Exit status: 0 stopped by SIGINT/SIGTERM, 1 runtime error, 2 usage or configuration error.

#include <chrono>
#include <cstdio>
#include <optional>
#include <string>
#include <vector>

#include <lcm/lcm-cpp.hpp>

#include "core/mapping/mapper.h"
#include "daemon/common/daemon_options.h"
#include "daemon/common/input_watch.h"
#include "daemon/common/run_loop.h"
#include "daemon/common/yaml_config.h"
#include "daemon/mapper/mapper_config_loader.h"
#include "daemon/mapper/mapper_lcm_node.h"

namespace cblox {
namespace {

using Clock = std::chrono::steady_clock;

struct Args {
  DaemonOptions daemon;
  std::optional<std::string> pose_source, output_dir, load_map;
  std::optional<std::string> checkpoint_dir;  ///< --checkpoint-dir DIR over checkpoint.dir
  bool planning = false;                      ///< --planning: planning.enabled over the file
};

MapperProcessConfig buildConfig(const Args& args) {
  MapperProcessConfig config = loadDaemonConfig<MapperProcessConfig>(args.daemon, loadMapperConfig);
  if (args.pose_source) config.mapper.pose_source = parsePoseSource(*args.pose_source);
  if (args.output_dir) config.mapper.output_dir = *args.output_dir;
  if (args.checkpoint_dir) config.mapper.checkpoint.dir = *args.checkpoint_dir;
  if (args.planning) config.mapper.planning.enabled = true;
  if (const std::string e = config.validate(); !e.empty()) throw ConfigError(e);
  return config;
}

int run(const Args& args) {
  const MapperProcessConfig config = buildConfig(args);
  const MapperConfig& m = config.mapper;

  lcm::LCM lcm(config.lcm_url);
  if (!lcm.good()) {
    std::fprintf(stderr, "cblox-mapper: cannot open LCM (url '%s')\n", config.lcm_url.c_str());
    return 1;
  }
  Mapper mapper(m);
  if (args.load_map) {
    // Before any input arrives: the operator must see a map that cannot be loaded.
    const MapperReply loaded = mapper.loadMap(*args.load_map);
    if (!loaded.ok) throw ConfigError("--load-map: " + loaded.message);
    if (!args.daemon.quiet) {
      std::printf("mapper: %s%s\n", loaded.message.c_str(),
                  m.checkpoint.enabled()
                      ? ("; checkpoints go to " + m.checkpoint.dir + " (not resumed from)").c_str()
                      : "");
      std::fflush(stdout);
    }
  } else if (const std::optional<MapperReply> resumed = mapper.resumeFromCheckpoint()) {
    // An unreadable checkpoint is not silently replaced by an empty map: the operator decides
    // (repair or move it, or set checkpoint.resume: false).
    if (!resumed->ok) throw ConfigError(resumed->message);
    if (!args.daemon.quiet) {
      std::printf("mapper: %s\n", resumed->message.c_str());
      std::fflush(stdout);
    }
  }
  MapperNode node(config, &lcm, &mapper);
  node.attachMeshStream();  // before start: the worker's periodic tasks are fixed then
  std::string error;
  if (!mapper.start(&error)) {
    std::fprintf(stderr, "cblox-mapper: %s\n", error.c_str());
    return 1;
  }
  installStopHandlers();
  if (!args.daemon.quiet) {
    std::printf(
        "mapper: %s poses, %s integrator, voxel %.3f m, truncation %.3f m, %d thread(s); "
        "new subvolume every %d keyframes%s; output %s\n",
        poseSourceName(m.pose_source), integratorTypeName(m.integrator_type), m.layer.voxel_size,
        m.integrator.truncation_distance_m, m.integrator.num_threads,
        m.creation.max_keyframes_per_subvolume,
        m.pose_source == PoseSource::kGroundTruth
            ? (" (a keyframe every " + std::to_string(m.keyframe_every_n_frames) + " frames)")
                  .c_str()
            : "",
        mapper.outputDir().c_str());
    std::fflush(stdout);
  }

  // Input-silence health: depth frames and the poses of the configured source.
  InputWatch input_watch("cblox-mapper", config.input_silence_s);
  input_watch.watch(config.depth_channel);
  input_watch.watch(m.pose_source == PoseSource::kGroundTruth ? config.ground_truth_channel
                                                              : config.frame_pose_channel);
  node.messageGuard().setInputWatch(&input_watch);
  node.subscribe();

  const Clock::time_point start = Clock::now();
  uint64_t last_integrated = 0;
  Clock::time_point last_progress = start;
  auto progress = [&](const MapperStatus& s, const char* prefix) {
    const double dt = std::chrono::duration<double>(Clock::now() - last_progress).count();
    const double rate =
        dt > 0 ? static_cast<double>(s.frames_integrated - last_integrated) / dt : 0;
    last_integrated = s.frames_integrated;
    last_progress = Clock::now();
    std::printf(
        "mapper: %s%llu frames integrated (%.1f/s), %llu dropped, %llu rejected, "
        "%zu subvolumes (%llu fused), %zu blocks, %.1f MiB, integration median %.1f ms p99 "
        "%.1f ms\n",
        prefix, static_cast<unsigned long long>(s.frames_integrated), rate,
        static_cast<unsigned long long>(s.frames_dropped),
        static_cast<unsigned long long>(s.frames_rejected), s.num_submaps,
        static_cast<unsigned long long>(s.fusion.fused), s.num_blocks,
        static_cast<double>(s.memory_bytes) / 1048576.0, s.integration_ms_median,
        s.integration_ms_p99);
    std::fflush(stdout);
  };

  SystemdNotifier notifier;
  std::vector<PeriodicTask> tasks{{config.status_period_s, 0.0, [&] {
                                     const MapperStatus s = mapper.status();
                                     node.publishStatus(s);
                                     node.publishHeartbeat(s, "running");
                                     notifier.status(
                                         std::to_string(s.frames_integrated) +
                                         " frames integrated, " + std::to_string(s.num_submaps) +
                                         " subvolumes, " + std::to_string(s.num_blocks) + " blocks");
                                   }}};
  if (!args.daemon.quiet) {
    tasks.push_back({config.progress_period_s, config.progress_period_s,
                     [&] { progress(mapper.status(), ""); }});
  }
  const int exit_code = serveUntilStopped(lcm, "cblox-mapper", tasks, &notifier);
  input_watch.stopWatching();  // the last heartbeat says "stopped", not "input silent"
  mapper.stop();  // finishes the frame in hand and the export in hand
  const MapperStatus s = mapper.status();
  node.publishStatus(s);
  node.publishHeartbeat(s, "stopped");
  if (!args.daemon.quiet) progress(s, "stopped: ");
  return exit_code;
}

}  // namespace
}  // namespace cblox

int main(int argc, char** argv) {
  cblox::Args args;
  CLI::App app{
      "cblox-mapper: the dense mapper process: integrates the depth frames of CBLOX_DEPTH into\n"
      "a collection of TSDF subvolumes at the poses of CBLOX_GT_POSE or of the tracker.\n"
      "Runs until SIGINT/SIGTERM. Commands arrive on CBLOX_CMD (see cblox-ctl).\n"
      "Exit status: 0 stopped by signal, 1 runtime error, 2 usage/configuration error.",
      "cblox-mapper"};
  cblox::addDaemonOptions(app, &args.daemon, "config/mapper.yaml");
  app.add_option("--pose-source", args.pose_source, "ground_truth | tracker")->type_name("SOURCE");
  app.add_option("--output-dir", args.output_dir, "where exports go (paths inside it only)")
      ->type_name("DIR");
  app.add_option("--load-map", args.load_map,
                 "load this saved map directory (cblox-ctl save-map) before serving")
      ->type_name("DIR");
  app.add_option("--checkpoint-dir", args.checkpoint_dir,
                 "checkpoint directory of the map (over checkpoint.dir; the systemd unit\n"
                 "gives /var/lib/cblox/checkpoint/mapper)")
      ->type_name("DIR");
  app.add_flag("--planning", args.planning,
               "keep distance fields and answer planners (planning.enabled: true, over the\n"
               "configuration file)");
  if (const std::optional<int> code = cblox::parseCommandLine(app, argc, argv)) return *code;
  return cblox::runProcess("cblox-mapper", [&] { return cblox::run(args); });
}
