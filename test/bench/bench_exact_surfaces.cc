// cblox-bench-exact-surfaces: the projective integrator against Open3D's ScalableTSDFVolume
// on the analytic room (cblox-integrate's synthetic-room source: 6 x 4 x 3 m with a table,
// a sphere and a pillar, a 60-frame orbit at 640x480, f = 525 px, exact depth and colour),
// at the settings of cblox-bench-integrators (voxel 2 cm, truncation 8 cm, depth cut at
// 4 m): ms per frame, 1 and 2 threads, in the same rounds, and the error of every mesh
// vertex against the exact surfaces (|signed distance| to the nearest primitive).
//
//   build/test/bench/cblox-bench-exact-surfaces [--repeats R] [--frames N]
//
// Exit status: 0; 3 when built without the Open3D peer (our rows are printed, no ratio);
// 2 on a usage error.

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <string>
#include <vector>

#include <CLI/CLI.hpp>

#include "core/eval/trajectory_metrics.h"
#include "core/integrator/projective_tsdf_integrator.h"
#include "core/mesh/mesh_integrator.h"
#include "daemon/common/cli.h"
#include "drivers/synthetic/demo_room_orbit.h"
#include "test/bench/bench_frames.h"
#include "test/bench/bench_stats.h"
#include "test/bench/integrator_bench_settings.h"
#ifdef CBLOX_HAVE_OPEN3D
#include "test/bench/open3d_peer.h"
#endif

namespace cblox::bench {
namespace {

// DemoRoomOrbit's frames (config/integrate.yaml's synthetic section), depth cut at kMaxDepth.
BenchSequence renderRoom(SyntheticDepthSource* source) {
  BenchSequence seq;
  seq.intrinsics = source->camera().intrinsics();
  SyntheticFrame frame;
  while (source->next(&frame)) {
    for (float& d : frame.depth.data) d = d > kMaxDepth ? 0.0f : d;  // as Open3D's depth_trunc
    seq.frames.push_back({frame.T_G_C, std::move(frame.depth), std::move(frame.color)});
  }
  return seq;
}

struct Row {
  std::string name;
  int threads = 1;
  std::vector<double> frame_ms;
  std::vector<Eigen::Vector3d> vertices;
};

Row runProjective(const BenchSequence& seq, int threads) {
  Row row{"projective", threads, {}, {}};
  TsdfLayer layer(LayerConfig{kVoxelSize, 8});
  ProjectiveTsdfIntegrator integrator(benchIntegratorConfig(threads), &layer);
  const PinholeCamera camera(seq.intrinsics);
  for (const BenchFrame& frame : seq.frames) {
    const auto start = std::chrono::steady_clock::now();
    integrator.integrateDepthImage(frame.T_G_C.cast<float>(), frame.depth, camera, &frame.color);
    row.frame_ms.push_back(
        std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start)
            .count());
  }
  MeshConfig mesh_config;
  mesh_config.num_threads = threads;
  MeshIntegrator mesher(layer, mesh_config);
  mesher.update(false, true);
  for (const Eigen::Vector3f& v : mesher.extractMesh(true).vertices) {
    row.vertices.push_back(v.cast<double>());
  }
  return row;
}

void printRow(const Row& row, const AnalyticScene& room) {
  std::vector<double> errors;
  for (const Eigen::Vector3d& v : row.vertices) errors.push_back(std::abs(room.signedDistance(v)));
  const double within_voxel =
      static_cast<double>(
          std::count_if(errors.begin(), errors.end(), [](double e) { return e <= kVoxelSize; })) /
      static_cast<double>(std::max<size_t>(errors.size(), 1));
  const ErrorStatistics stats = computeErrorStatistics(std::move(errors));
  std::printf("| %s | %d | %.2f | %.2f | %zu | %.2f mm | %.2f mm | %.2f mm | %.2f %% |\n",
              row.name.c_str(), row.threads, median(row.frame_ms), percentile(row.frame_ms, 0.95),
              row.vertices.size(), 1e3 * stats.rmse, 1e3 * stats.median, 1e3 * stats.p90,
              100.0 * within_voxel);
}

}  // namespace
}  // namespace cblox::bench

int main(int argc, char** argv) {
  using namespace cblox::bench;
  int repeats = 3;
  int frames = 60;
  CLI::App app{
      "cblox-bench-exact-surfaces: the projective integrator and Open3D's ScalableTSDFVolume on\n"
      "the analytic room with exact depth: ms per frame in the same rounds, and every mesh\n"
      "vertex's error against the exact surfaces.",
      "cblox-bench-exact-surfaces"};
  app.add_option("--repeats", repeats, "rounds (the fastest per frame counts)")
      ->capture_default_str();
  app.add_option("--frames", frames, "frames of the orbit")->capture_default_str();
  if (const std::optional<int> code = cblox::parseCommandLine(app, argc, argv)) return *code;
  if (frames < 1) {
    std::fprintf(stderr, "--frames must be >= 1\n");
    return 2;
  }
  repeats = std::max(1, repeats);
  cblox::DemoRoomOrbit orbit;
  orbit.frames = frames;
  cblox::SyntheticDepthSource source = orbit.source();
  const cblox::AnalyticScene& room = source.scene();
  const BenchSequence seq = renderRoom(&source);
  std::printf(
      "analytic room, %zu frames 640x480; voxel %.3f m, truncation %.3f m, depth cut at "
      "%.1f m; %d rounds\n",
      seq.frames.size(), kVoxelSize, kTruncation, kMaxDepth, repeats);
  std::vector<Row> rows;
  for (int round = 0; round < repeats; ++round) {
    size_t r = 0;
    const auto add = [&](Row row) {
      if (round == 0) {
        rows.push_back(std::move(row));
      } else {
        keepFastestPerFrame(&rows[r].frame_ms, row.frame_ms);
      }
      ++r;
    };
    for (int threads : {1, 2}) {
      std::printf("round %d of %d: projective, %d thread(s) ...\n", round + 1, repeats, threads);
      std::fflush(stdout);
      add(runProjective(seq, threads));
#ifdef CBLOX_HAVE_OPEN3D
      std::printf("round %d of %d: Open3D, %d thread(s) ...\n", round + 1, repeats, threads);
      std::fflush(stdout);
      Open3dResult peer = runOpen3dScalableTsdf(seq, kVoxelSize, kTruncation, kMaxDepth, threads);
      add(Row{"Open3D ScalableTSDFVolume", threads, std::move(peer.frame_ms),
              std::move(peer.mesh_positions)});
#endif
    }
  }
  std::printf(
      "\n| integrator | threads | median ms/frame | p95 ms | mesh vertices | vertex RMSE | median "
      "| p90 | within one voxel |\n|---|---|---|---|---|---|---|---|---|\n");
  for (const Row& row : rows) printRow(row, room);
#ifdef CBLOX_HAVE_OPEN3D
  std::printf("\nprojective / Open3D (median ms per frame, same threads, same rounds):\n");
  for (size_t i = 0; i + 1 < rows.size(); i += 2) {
    std::printf("  %d thread(s): %.2f\n", rows[i].threads,
                median(rows[i].frame_ms) / median(rows[i + 1].frame_ms));
  }
  return 0;
#else
  std::fprintf(stderr, "cblox-bench-exact-surfaces: built without the Open3D peer (exit %d)\n",
               kExitNoOpen3d);
  return kExitNoOpen3d;
#endif
}
