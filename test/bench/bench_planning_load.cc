// cblox-bench-planning-load: what a loaded or resumed map costs before a planner can ask it.
// The analytic room is mapped by a Mapper from --frames exact frames of its orbit (640x480,
// ground-truth poses, --voxel voxels, a new subvolume every 20 frames) and saved (save_map);
// then, --repeats times, a mapper with planning on loads it (Mapper::loadMap, which also
// computes every subvolume's distance field from scratch: the load is its reported seconds
// less that refresh, PlanningMap::refreshMs; the bytes on disk). The alternative, storing
// the fields with the map, would read their bytes (PlanningMap::memoryBytes) on top of the
// TSDF's: printed at the load's own rate as "stored fields, estimated read". The fastest
// repeat counts.
//
//   build/test/bench/cblox-bench-planning-load [--frames 60] [--voxel 0.04] [--repeats 3]
//
// Exit status: 0; 1 when a step fails (named); 2 on a usage error.

#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <future>
#include <memory>
#include <string>

#include <CLI/CLI.hpp>

#include "core/mapping/mapper.h"
#include "daemon/common/cli.h"
#include "drivers/synthetic/demo_room_orbit.h"

namespace cblox::bench {
namespace {

MapperConfig benchConfig(const std::filesystem::path& output_dir, float voxel) {
  MapperConfig config;
  config.layer = LayerConfig{voxel, 8};
  config.output_dir = output_dir.string();
  config.keyframe_every_n_frames = 5;
  config.creation.max_keyframes_per_subvolume = 4;  // a new subvolume every 20 frames
  config.worker_sched_idle = false;
  config.worker_niceness = 0;
  config.integrator.max_integration_time_s = 0.0;  // every frame whole
  return config;
}

/// Maps the room and saves it as `name` in the output directory; false with a message.
bool mapAndSave(const MapperConfig& config, int frames, const std::string& name) {
  Mapper mapper(config);
  std::string error;
  if (!mapper.start(&error)) {
    std::fprintf(stderr, "cblox-bench-planning-load: mapper: %s\n", error.c_str());
    return false;
  }
  DemoRoomOrbit orbit;
  orbit.frames = frames;
  SyntheticDepthSource source = orbit.source();
  SyntheticFrame frame;
  for (int64_t id = 0; source.next(&frame); ++id) {
    DepthFrame depth;
    depth.utime = frame.timestamp_ns / 1000;
    depth.frame_id = id;
    depth.depth = frame.depth;
    depth.intrinsics = orbit.intrinsics();
    depth.min_depth_m = 0.1f;
    depth.max_depth_m = 4.0f;
    TimedPose pose;
    pose.utime = depth.utime;
    pose.T_G_C = frame.T_G_C;
    if (!mapper.onDepthFrame(std::move(depth)) || !mapper.onFramePose(pose) ||
        !mapper.waitUntilIdle(std::chrono::seconds(120))) {
      std::fprintf(stderr, "cblox-bench-planning-load: frame %lld was not integrated\n",
                   static_cast<long long>(id));
      return false;
    }
    std::fprintf(stderr, "\rmapping the room: frame %lld of %d", static_cast<long long>(id + 1),
                 frames);
  }
  std::fprintf(stderr, "\n");
  MapperCommand save;
  save.id = 1;
  save.name = "save_map";
  save.args["path"] = name;
  auto promise = std::make_shared<std::promise<MapperReply>>();
  std::future<MapperReply> reply = promise->get_future();
  mapper.onCommand(save, [promise](const MapperReply& r) { promise->set_value(r); });
  const MapperReply saved = reply.get();
  if (!saved.ok) {
    std::fprintf(stderr, "cblox-bench-planning-load: save_map: %s\n", saved.message.c_str());
    return false;
  }
  return true;
}

}  // namespace
}  // namespace cblox::bench

int main(int argc, char** argv) {
  using namespace cblox;
  using namespace cblox::bench;
  int frames = 60, repeats = 3;
  float voxel = 0.04f;
  CLI::App app{
      "cblox-bench-planning-load: a saved room loaded into a mapper with planning on: load\n"
      "time, the distance fields' rebuild time, and the stored-field alternative."};
  app.add_option("--frames", frames, "frames of the orbit")->check(CLI::Range(1, 100000))
      ->capture_default_str();
  app.add_option("--voxel", voxel, "voxel size, metres")->check(CLI::Range(0.005f, 1.0f))
      ->capture_default_str();
  app.add_option("--repeats", repeats, "loads (the fastest counts)")->check(CLI::Range(1, 100))
      ->capture_default_str();
  if (const std::optional<int> code = parseCommandLine(app, argc, argv)) return *code;

  const std::filesystem::path dir = std::filesystem::temp_directory_path() /
                                    ("cblox-bench-planning-load-" + std::to_string(::getpid()));
  std::filesystem::create_directories(dir);
  MapperConfig config = benchConfig(dir, voxel);
  if (!mapAndSave(config, frames, "room_map")) return 1;

  config.planning.enabled = true;
  double best_load = 1e30, best_rebuild = 1e30;
  PlanningMapStats fields;
  MapperReply loaded;
  for (int r = 0; r < repeats; ++r) {
    Mapper mapper(config);
    const MapperReply reply = mapper.loadMap((dir / "room_map").string());
    if (!reply.ok) {
      std::fprintf(stderr, "cblox-bench-planning-load: load: %s\n", reply.message.c_str());
      return 1;
    }
    const PlanningMap& planning = *mapper.planningMap();
    const double rebuild = planning.refreshMs().last() / 1000.0;  // the load's one refresh
    const double load = std::stod(reply.value("seconds")) - rebuild;
    best_load = std::min(best_load, load);
    best_rebuild = std::min(best_rebuild, rebuild);
    fields = planning.stats();
    loaded = reply;
    std::fprintf(stderr, "load %d of %d: map %.3f s, fields %.3f s\n", r + 1, repeats, load,
                 rebuild);
  }
  std::filesystem::remove_all(dir);

  const double bytes = std::stod(loaded.value("bytes"));
  const double rate = bytes / std::max(best_load, 1e-9);
  std::printf("| voxel | frames | subvolumes | TSDF blocks | map on disk | load | fields' rebuild "
              "| field bytes | stored fields, estimated read |\n|---|---|---|---|---|---|---|---|"
              "---|\n");
  std::printf("| %.3f m | %d | %s | %s | %.1f MiB | %.3f s | %.3f s | %.1f MiB | %.3f s |\n",
              static_cast<double>(voxel), frames, loaded.value("submaps").c_str(),
              loaded.value("blocks").c_str(), bytes / 1048576.0, best_load, best_rebuild,
              static_cast<double>(fields.memory_bytes) / 1048576.0,
              static_cast<double>(fields.memory_bytes) / rate);
  return 0;
}
