// Simulator render benchmark: time per stereo + depth frame at 752x480 for every built-in
// scene, with the depth camera registered to the left camera (two ray-traced views: left
// with colour and depth, right) and with a separate depth camera (three views), for 1 and
// 2 render threads. The simulator must beat real time at 20 Hz (50 ms per frame).
//
//   cblox-bench-sim-render [--frames N] [--repeats R] [--json FILE] [--scene room|hall|town]
//
// Frames are spread evenly over each scene's loop trajectory; each is rendered R times
// (default 3) and the fastest is kept, as the host is shared.

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <fstream>
#include <optional>
#include <string>
#include <vector>

#include <CLI/CLI.hpp>
#include <nlohmann/json.hpp>

#include "daemon/common/cli.h"
#include "drivers/sim/builtin_scenes.h"
#include "drivers/sim/sim_renderer.h"

namespace cblox {
namespace {

using Clock = std::chrono::steady_clock;

struct Row {
  std::string scene, rig;
  int threads;
  size_t triangles;
  double build_ms, median_ms, p90_ms, max_ms;
};

double percentile(std::vector<double> v, double p) {
  std::sort(v.begin(), v.end());
  const size_t i = std::min(v.size() - 1, static_cast<size_t>(p * (v.size() - 1) + 0.5));
  return v[i];
}

int run(int argc, char** argv) {
  int frames = 60, repeats = 3;
  std::string json_path, only;
  CLI::App app{
      "cblox-bench-sim-render: render time per stereo + depth frame (752x480) of the built-in\n"
      "scenes, registered and separate depth camera, 1 and 2 threads.",
      "cblox-bench-sim-render"};
  app.add_option("--frames", frames, "frames per configuration")->capture_default_str();
  app.add_option("--repeats", repeats, "renders per frame (the fastest counts)")
      ->capture_default_str();
  app.add_option("--json", json_path, "also write the figures as JSON")->type_name("FILE");
  app.add_option("--scene", only, "one built-in scene only")->type_name("NAME");
  if (const std::optional<int> code = parseCommandLine(app, argc, argv)) return *code;
  frames = std::max(1, frames);
  repeats = std::max(1, repeats);
  std::vector<Row> rows;
  for (const std::string& name : builtinSceneNames()) {
    if (!only.empty() && name != only) continue;
    const BuiltinScene scene = makeBuiltinScene(name);
    const auto t0 = Clock::now();
    std::string error;
    std::shared_ptr<const TriangleMeshRaycaster> raycaster =
        TriangleMeshRaycaster::create(scene.mesh, &error);
    const double build_ms = std::chrono::duration<double, std::milli>(Clock::now() - t0).count();
    if (raycaster == nullptr) {
      std::fprintf(stderr, "%s: %s\n", name.c_str(), error.c_str());
      return 1;
    }
    const StampedTrajectory trajectory =
        makeSceneTrajectory(scene, TrajectoryKind::kLoop, 20.0);
    for (const bool separate_depth : {false, true}) {
      for (const int threads : {1, 2}) {
        SimRendererConfig config;  // 752x480 EuRoC-like rig
        config.num_threads = threads;
        config.rig.depth_max_m = scene.depth_max_m;
        config.texture.base_wavelength_m = scene.texture_wavelength_m;
        if (separate_depth) {
          config.rig.depth = config.rig.stereo;
          config.rig.T_L_D =
              Transformationd(Eigen::Quaterniond::Identity(), Eigen::Vector3d(0.03, 0.0, 0.0));
        }
        const SimRenderer renderer(raycaster, config);
        SimImages images;
        renderer.render(trajectory.front().T_G_C, &images);  // warm-up
        std::vector<double> ms;
        const size_t step = std::max<size_t>(1, trajectory.size() / static_cast<size_t>(frames));
        for (int f = 0; f < frames; ++f) {
          const Transformationd& pose =
              trajectory[std::min(trajectory.size() - 1, static_cast<size_t>(f) * step)].T_G_C;
          // Best of `repeats`: interference from other tenants of the host only adds time.
          double best = 1e30;
          for (int r = 0; r < repeats; ++r) {
            const auto start = Clock::now();
            renderer.render(pose, &images);
            best = std::min(best,
                            std::chrono::duration<double, std::milli>(Clock::now() - start).count());
          }
          ms.push_back(best);
        }
        const Row row{name, separate_depth ? "stereo+separate depth (3 views)"
                                           : "stereo+registered depth (2 views)",
                      threads, scene.mesh.numTriangles(), build_ms, percentile(ms, 0.5),
                      percentile(ms, 0.9), *std::max_element(ms.begin(), ms.end())};
        std::printf("%-5s %-34s threads %d: median %6.1f ms  p90 %6.1f ms  max %6.1f ms  "
                    "(%5.1f frames/s, %zu triangles, BVH %.0f ms)\n",
                    row.scene.c_str(), row.rig.c_str(), threads, row.median_ms, row.p90_ms,
                    row.max_ms, 1000.0 / row.median_ms, row.triangles, row.build_ms);
        std::fflush(stdout);
        rows.push_back(row);
      }
    }
  }
  if (!json_path.empty()) {
    nlohmann::ordered_json json = nlohmann::ordered_json::array();
    for (const Row& r : rows) {
      json.push_back({{"scene", r.scene},
                      {"rig", r.rig},
                      {"threads", r.threads},
                      {"triangles", r.triangles},
                      {"bvh_build_ms", r.build_ms},
                      {"median_ms", r.median_ms},
                      {"p90_ms", r.p90_ms},
                      {"max_ms", r.max_ms}});
    }
    std::ofstream(json_path) << json.dump(2) << "\n";
  }
  return 0;
}

}  // namespace
}  // namespace cblox

int main(int argc, char** argv) { return cblox::run(argc, argv); }
