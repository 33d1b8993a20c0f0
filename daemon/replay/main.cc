// cblox-replay: plays an LCM log (recorded with lcm-logger, e.g. scripts/record.sh) through
// the tracker and the mapper in one process, as fast as the CPU allows, deterministically:
// the same log and configs give the same poses and the same mesh, bit for bit.
//
//   cblox-replay run.lcmlog --out out/replay --pose-source tracker --initial-pose-from-gt
//   cblox-replay run.lcmlog --out out/gt --mapper-config config/mapper.yaml
//
// Reads the sensor channels of the configs (CBLOX_STEREO or CBLOX_DEPTH for the tracker,
// CBLOX_DEPTH for the mapper, CBLOX_GT_POSE where the configs use ground truth); other
// channels are counted and not used. Writes into DIR: mesh.ply (the mapper's global mesh),
// frame_poses.tum and keyframes.tum (tracker mode; TUM format, keyframes at their final
// poses) and replay.json (counts, rates, the tracker's and mapper's status).
// Exit status: 0 done (also when stopped by SIGINT/SIGTERM: what was read is mapped and
// written), 1 runtime error, 2 usage or configuration error.

#include <unistd.h>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <optional>
#include <string>

#include <CLI/CLI.hpp>
#include <nlohmann/json.hpp>

#include "core/io/tum_trajectory.h"
#include "daemon/common/cli.h"
#include "daemon/common/run_loop.h"
#include "daemon/common/yaml_config.h"
#include "daemon/mapper/mapper_config_loader.h"
#include "daemon/replay/log_replayer.h"
#include "daemon/tracker/tracker_config.h"
#include "daemon/tracker/tracker_options.h"
#include "daemon/tracker/tracker_vocabulary.h"

namespace cblox {
namespace {

struct Args {
  std::string log, out;
  std::optional<std::string> mapper_config, tracker_config, pose_source;
  TrackerOptions tracker;
  bool no_mesh = false;
  bool quiet = false;
  double progress_period_s = 1.0;
};

ReplayConfig buildConfig(const Args& args) {
  ReplayConfig config;
  config.log_path = args.log;
  if (args.mapper_config) config.mapper = loadMapperConfig(loadYamlFile(*args.mapper_config));
  if (args.pose_source) config.mapper.mapper.pose_source = parsePoseSource(*args.pose_source);
  config.mapper.mapper.output_dir = args.out;
  if (const std::string e = config.mapper.validate(); !e.empty()) throw ConfigError(e);
  if (args.tracker_config) {
    config.tracker = loadTrackerConfig(loadYamlFile(*args.tracker_config));
  }
  applyTrackerOptions(args.tracker, &config.tracker);
  return config;
}

std::string clockText(double seconds) {
  if (!std::isfinite(seconds) || seconds < 0) return "--:--";
  const long s = std::lround(seconds);
  char text[32];
  std::snprintf(text, sizeof(text), "%ld:%02ld", s / 60, s % 60);
  return text;
}

// One progress line: a bar on a terminal (redrawn in place), plain lines otherwise.
void printProgress(const ReplayProgress& p, bool tty) {
  const double rate = p.elapsed_s > 0 ? static_cast<double>(p.frames) / p.elapsed_s : 0.0;
  const double speed = p.elapsed_s > 0 ? p.log_elapsed_s / p.elapsed_s : 0.0;
  const double eta = p.fraction > 0 ? p.elapsed_s * (1.0 - p.fraction) / p.fraction : NAN;
  constexpr int kWidth = 24;
  const int filled = static_cast<int>(std::lround(p.fraction * kWidth));
  std::string bar(static_cast<size_t>(filled), '#');
  bar.resize(kWidth, '.');
  std::fprintf(stdout, "%sreplay: [%s] %3.0f%%  %llu frames  %.1f frames/s  %.2fx real time  ETA %s%s",
               tty ? "\r" : "", bar.c_str(), 100.0 * p.fraction,
               static_cast<unsigned long long>(p.frames), rate, speed, clockText(eta).c_str(),
               tty ? "" : "\n");
  std::fflush(stdout);
}

StampedTrajectory toTrajectory(const std::vector<ReplayPose>& poses) {
  StampedTrajectory out;
  for (const ReplayPose& p : poses) {
    const double t = static_cast<double>(p.utime) * 1e-6;
    if (!out.empty() && t <= out.back().timestamp_s) continue;  // TUM: strictly increasing
    out.push_back(StampedPose{t, p.T_G_C});
  }
  return out;
}

nlohmann::json summaryJson(const ReplaySummary& s, const ReplayConfig& config) {
  nlohmann::json j;
  j["log"] = config.log_path;
  j["pose_source"] = poseSourceName(config.mapper.mapper.pose_source);
  j["events"] = s.events;
  j["tracker_frames"] = s.tracker_frames;
  j["depth_frames"] = s.depth_frames;
  j["ground_truth_poses"] = s.ground_truth_poses;
  j["ignored_events"] = s.ignored;
  j["messages_refused"] = s.refused;
  j["handler_errors"] = s.handler_errors;
  j["damaged_regions"] = s.damaged_regions;
  j["skipped_bytes"] = s.skipped_bytes;
  j["stopped_by_signal"] = s.stopped;
  j["wall_s"] = s.wall_s;
  j["log_span_s"] = s.log_span_s;
  const uint64_t frames =
      config.mapper.mapper.pose_source == PoseSource::kTracker ? s.tracker_frames : s.depth_frames;
  j["frames_per_s"] = s.wall_s > 0 ? static_cast<double>(frames) / s.wall_s : 0.0;
  j["speed_vs_real_time"] = s.wall_s > 0 ? s.log_span_s / s.wall_s : 0.0;
  j["mapper"] = {{"frames_integrated", s.mapper.frames_integrated},
                 {"frames_rejected", s.mapper.frames_rejected},
                 {"frames_dropped", s.mapper.frames_dropped},
                 {"keyframes_applied", s.mapper.keyframes_applied},
                 {"subvolumes", s.mapper.num_submaps},
                 {"blocks", s.mapper.num_blocks},
                 {"memory_bytes", s.mapper.memory_bytes},
                 {"fusions_done", s.mapper.fusion.fused}};
  for (size_t i = 0; i < kNumInputProblems; ++i) {
    if (s.mapper.problems[i] > 0) {
      j["mapper"]["problems"][inputProblemName(static_cast<InputProblem>(i))] = s.mapper.problems[i];
    }
  }
  if (config.mapper.mapper.pose_source == PoseSource::kTracker) {
    j["tracker"] = {{"frames_processed", s.tracker.frames_processed},
                    {"frames_tracked", s.tracker.frames_tracked},
                    {"frames_lost", s.tracker.frames_lost},
                    {"frames_rejected", s.tracker.frames_rejected},
                    {"keyframes", s.tracker.keyframes},
                    {"loops_closed", s.tracker.loops_closed},
                    {"frame_ms_median", s.tracker.frame_ms_median},
                    {"frame_ms_p95", s.tracker.frame_ms_p95}};
    for (size_t i = 0; i < kNumTrackerProblems; ++i) {
      if (s.tracker.problems[i] > 0) {
        j["tracker"]["problems"][trackerProblemName(static_cast<TrackerProblem>(i))] =
            s.tracker.problems[i];
      }
    }
  }
  return j;
}

int run(const Args& args) {
  installStopHandlers();
  const ReplayConfig config = buildConfig(args);
  const bool tracker_mode = config.mapper.mapper.pose_source == PoseSource::kTracker;
  const std::unique_ptr<BinaryVocabulary> vocabulary =
      tracker_mode ? loadTrackerVocabulary(config.tracker.vocabulary) : nullptr;
  std::error_code ec;
  std::filesystem::create_directories(args.out, ec);
  if (ec) throw std::runtime_error("cannot create " + args.out + ": " + ec.message());

  LogReplayer replayer(config, vocabulary.get());
  if (!args.quiet) {
    std::printf("replay: %s -> %s (%s poses%s)\n", args.log.c_str(), args.out.c_str(),
                poseSourceName(config.mapper.mapper.pose_source),
                tracker_mode ? (std::string(", tracker ") +
                                trackerModeName(config.tracker.tracker.mode))
                                   .c_str()
                             : "");
  }
  const bool tty = ::isatty(STDOUT_FILENO) != 0;
  const ReplaySummary s = replayer.run(
      [&](const ReplayProgress& p) {
        if (!args.quiet) printProgress(p, tty);
      },
      args.progress_period_s, &g_stop_requested);
  if (!args.quiet && tty) std::printf("\n");

  int status = 0;
  if (!args.no_mesh) {
    MapperCommand export_mesh;
    export_mesh.name = "export_mesh";
    export_mesh.args["path"] = "mesh.ply";
    const MapperReply reply = replayer.command(export_mesh);
    if (!reply.ok) {
      std::fprintf(stderr, "cblox-replay: mesh export failed: %s\n", reply.message.c_str());
      status = 1;
    }
  }
  std::string error;
  const std::filesystem::path out(args.out);
  if (tracker_mode) {
    for (const auto& [name, poses] :
         {std::pair{"frame_poses.tum", &s.frame_poses}, std::pair{"keyframes.tum", &s.keyframes}}) {
      if (!writeTumTrajectory((out / name).string(), toTrajectory(*poses), &error)) {
        std::fprintf(stderr, "cblox-replay: %s\n", error.c_str());
        status = 1;
      }
    }
  }
  std::ofstream json(out / "replay.json");
  json << summaryJson(s, config).dump(2) << "\n";
  if (!json) {
    std::fprintf(stderr, "cblox-replay: cannot write %s\n", (out / "replay.json").c_str());
    status = 1;
  }
  if (!args.quiet) {
    std::printf(
        "replay: %llu events in %.1f s (log %.1f s: %.2fx real time); %llu tracker frames, %llu "
        "depth frames; %llu integrated, %llu rejected; %zu subvolumes, %zu blocks",
        static_cast<unsigned long long>(s.events), s.wall_s, s.log_span_s,
        s.wall_s > 0 ? s.log_span_s / s.wall_s : 0.0,
        static_cast<unsigned long long>(s.tracker_frames),
        static_cast<unsigned long long>(s.depth_frames),
        static_cast<unsigned long long>(s.mapper.frames_integrated),
        static_cast<unsigned long long>(s.mapper.frames_rejected), s.mapper.num_submaps,
        s.mapper.num_blocks);
    if (tracker_mode) {
      std::printf("; %llu keyframes, %llu loops, %llu lost",
                  static_cast<unsigned long long>(s.tracker.keyframes),
                  static_cast<unsigned long long>(s.tracker.loops_closed),
                  static_cast<unsigned long long>(s.tracker.frames_lost));
    }
    std::printf("%s\n", s.stopped ? " (stopped by signal)" : "");
    for (const auto& [channel, n] : s.ignored) {
      std::printf("replay: %llu events of %s not used\n", static_cast<unsigned long long>(n),
                  channel.c_str());
    }
  }
  for (const auto& [kind, n] : s.refused) {
    std::fprintf(stderr, "cblox-replay: %llu message(s) refused (%s)%s\n",
                 static_cast<unsigned long long>(n), kind.c_str(),
                 kind == "fingerprint_mismatch"
                     ? ": the log holds another version of the cblox message types than this "
                       "build (record it again, or replay it with the build that recorded it)"
                     : "");
  }
  if (s.damaged_regions > 0) {
    std::fprintf(stderr,
                 "cblox-replay: %llu damaged stretch(es) of the log (%llu bytes) skipped: the log "
                 "was cut short or damaged\n",
                 static_cast<unsigned long long>(s.damaged_regions),
                 static_cast<unsigned long long>(s.skipped_bytes));
  }
  return status;
}

}  // namespace
}  // namespace cblox

int main(int argc, char** argv) {
  cblox::Args args;
  CLI::App app{
      "cblox-replay: plays an LCM log through the tracker and the mapper in one process, as\n"
      "fast as the CPU allows and deterministically (same log and configs: same poses and mesh,\n"
      "bit for bit). Writes DIR/mesh.ply, DIR/frame_poses.tum, DIR/keyframes.tum (tracker\n"
      "mode) and DIR/replay.json.\n"
      "Exit status: 0 done (also after SIGINT: what was read is written), 1 runtime error,\n"
      "2 usage or configuration error."};
  app.add_option("log", args.log, "the log (lcm-logger's format)")->required();
  app.add_option("--out", args.out, "output directory (created)")->required();
  app.add_option("--mapper-config", args.mapper_config, "config/mapper.yaml style file");
  app.add_option("--tracker-config", args.tracker_config, "config/tracker.yaml style file");
  app.add_option("--pose-source", args.pose_source,
                 "tracker | ground_truth (default: the mapper config's)");
  cblox::addTrackerOptions(app, &args.tracker);
  app.add_flag("--no-mesh", args.no_mesh, "do not export the mesh");
  app.add_option("--progress-period", args.progress_period_s, "seconds between progress lines")
      ->check(cblox::finiteNumber(cblox::NumberBound::kPositive));
  app.add_flag("--quiet", args.quiet, "no progress or summary on stdout");
  if (const std::optional<int> code = cblox::parseCommandLine(app, argc, argv)) return *code;
  return cblox::runProcess("cblox-replay", [&] { return cblox::run(args); });
}
