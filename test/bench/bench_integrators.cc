// cblox-bench-integrators: ms per frame of the simple, fast and projective integrators on
// the 50 frames of ../shared/data/7scenes-rgbd-50 (voxel 2 cm, truncation 4 voxels, max
// depth 4 m), 1 and 2 threads, 8^3 vs 16^3 blocks, the fast integrator also with the paper's
// hash set and with voxblox's start cells of half a voxel, the projective integrator also one
// voxel at a time (1 thread, IntegratorConfig::vectorized off), and two peers on the same frames
// in the same run: Open3D's ScalableTSDFVolume (when built with Open3D) and voxblox's own
// FastTsdfIntegrator (when built with voxblox: see test/bench/CMakeLists.txt); mesh
// extraction time, and the accuracy of each mesh (voxblox's too) against the simple
// integrator's TSDF (the fused reference).
//
//   build/test/bench/cblox-bench-integrators [--data DIR] [--simple-frames N] [--repeats R]
//                                            [--json FILE]
//   build/test/bench/cblox-bench-integrators --only fast      # peak memory of one integrator
//
// Exit status: 0 with both peers; a peer that is not built gets no row and no ratio, says
// so, and the run ends with 3 when the Open3D peer is missing, 4 when the voxblox peer is
// missing, 5 when both are (every other figure is printed); 1 or 2 on a data or usage error
// (--only with a peer that is not built: 3 or 4 as well).
//
// Timing: R rounds (default 3); in each, every configuration runs once on a fresh volume,
// ours and the peers in turn, so a peer's ratio is measured seconds, not minutes, from its
// row (this host's speed drifts over minutes). Per frame the fastest round is kept
// (interference from other jobs only adds time), and the table gives the median and 95th
// percentile over the frames. The simple rows (the accuracy reference) run in round 1 only.

#include <sys/resource.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include <CLI/CLI.hpp>
#include <nlohmann/json.hpp>

#include "core/geometry/depth_to_point_cloud.h"
#include "core/integrator/projective_tsdf_integrator.h"
#include "core/integrator/ray_casting_integrator.h"
#include "core/mesh/mesh_integrator.h"
#include "core/tsdf/tsdf_interpolator.h"
#include "daemon/common/cli.h"
#include "drivers/dataset/seven_scenes_reader.h"
#include "test/bench/bench_frames.h"
#include "test/bench/bench_stats.h"
#include "test/bench/integrator_bench_settings.h"
#ifdef CBLOX_HAVE_OPEN3D
#include "test/bench/open3d_peer.h"
#endif
#ifdef CBLOX_HAVE_VOXBLOX
#include "test/bench/voxblox_peer.h"
#endif

namespace cblox::bench {
namespace {

double peakRssMiB() {
  rusage usage{};
  getrusage(RUSAGE_SELF, &usage);
  return usage.ru_maxrss / 1024.0;
}

struct Run {
  std::string name;
  int threads = 1;
  int voxels_per_side = 8;
  std::vector<double> frame_ms;
  size_t blocks = 0;
  double layer_mib = 0.0;
  double mesh_ms = 0.0;
  size_t mesh_vertices = 0;
  double rmse_to_reference_mm = -1.0;        // mesh vertices -> reference surface
  double mean_signed_to_reference_mm = 0.0;  // > 0: the surface lies in front of the reference's
  double reference_coverage = -1.0;          // share of reference vertices near this surface
  double unobserved_in_reference = -1.0;     // share of vertices where the reference is empty
  std::shared_ptr<TsdfLayer> layer;
  Mesh mesh;
  std::vector<double> conversion_ms;  // voxblox rows: depthToPointCloud alone, per frame
};

// Keeps, per frame, the faster of two runs of one configuration: the machine is shared,
// and interference only ever adds time.
void keepFastest(Run* best, const Run& again) {
  keepFastestPerFrame(&best->frame_ms, again.frame_ms);
  keepFastestPerFrame(&best->conversion_ms, again.conversion_ms);
  best->mesh_ms = std::min(best->mesh_ms, again.mesh_ms);
}

// kProjectivePortable: the projective integrator updating one voxel at a time
// (IntegratorConfig::vectorized off), to show what the AVX2 rows gain in the same run.
enum class Kind { kSimple, kFast, kProjective, kProjectivePortable };

// The name of a kind's rows (tables, JSON, progress lines).
const char* kindName(Kind kind) {
  switch (kind) {
    case Kind::kSimple:
      return "simple";
    case Kind::kFast:
      return "fast";
    case Kind::kProjective:
      return "projective";
    case Kind::kProjectivePortable:
      return "projective, one voxel at a time";
  }
  return "?";
}

// Marching cubes over the whole layer plus the connected extraction, with the run's
// threads; fills mesh, mesh_ms and mesh_vertices.
void meshRun(Run* run) {
  MeshConfig mesh_config;
  mesh_config.num_threads = run->threads;
  MeshIntegrator mesher(*run->layer, mesh_config);
  const auto start = std::chrono::steady_clock::now();
  mesher.update(false, true);
  run->mesh = mesher.extractMesh(true);
  run->mesh_ms =
      std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
  run->mesh_vertices = run->mesh.numVertices();
}

// A fast-integrator setting other than the default, shown beside it in the same rounds.
struct FastVariant {
  VisitedVoxelSet visited = VisitedVoxelSet::kBlockBitmap;
  float start_voxel_subsampling_factor = IntegratorConfig{}.start_voxel_subsampling_factor;
};

Run integrateOnce(const BenchSequence& seq, Kind kind, int threads, int voxels_per_side,
                  size_t max_frames, const FastVariant& variant) {
  Run run;
  run.name = kindName(kind);
  run.threads = threads;
  run.voxels_per_side = voxels_per_side;
  run.layer = std::make_shared<TsdfLayer>(LayerConfig{kVoxelSize, voxels_per_side});
  IntegratorConfig config = benchIntegratorConfig(threads);
  config.visited_voxel_set = variant.visited;
  config.start_voxel_subsampling_factor = variant.start_voxel_subsampling_factor;
  config.vectorized = kind != Kind::kProjectivePortable;
  if (variant.visited == VisitedVoxelSet::kApproxHashSet) run.name += " (paper hash set)";
  if (variant.start_voxel_subsampling_factor != IntegratorConfig{}.start_voxel_subsampling_factor) {
    char suffix[48];
    std::snprintf(suffix, sizeof(suffix), " (start factor %g)",
                  variant.start_voxel_subsampling_factor);
    run.name += suffix;
  }
  const PinholeCamera camera(seq.intrinsics);
  DepthConversionConfig conversion;
  conversion.min_depth_m = 0.1f;
  conversion.max_depth_m = kMaxDepth;
  std::unique_ptr<RayCastingIntegrator> rays;
  std::unique_ptr<ProjectiveTsdfIntegrator> projective;
  if (kind == Kind::kProjective || kind == Kind::kProjectivePortable) {
    projective = std::make_unique<ProjectiveTsdfIntegrator>(config, run.layer.get());
  } else {
    rays = std::make_unique<RayCastingIntegrator>(kind == Kind::kFast
                                                      ? RayCastingIntegrator::Mode::kFast
                                                      : RayCastingIntegrator::Mode::kSimple,
                                                  config, run.layer.get());
  }
  size_t count = 0;
  for (const BenchFrame& frame : seq.frames) {
    if (count++ >= max_frames) break;
    const Transformation T_G_C = frame.T_G_C.cast<float>();
    if (projective) {
      // The depth image is cut at kMaxDepth like the point cloud (and Open3D's depth_trunc).
      DepthImage depth = frame.depth;
      for (float& d : depth.data) d = d > kMaxDepth ? 0.0f : d;
      const auto start = std::chrono::steady_clock::now();
      projective->integrateDepthImage(T_G_C, depth, camera, &frame.color);
      run.frame_ms.push_back(
          std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start)
              .count());
    } else {
      // Timed: depth -> point cloud conversion plus integration (what a mapper does).
      const auto start = std::chrono::steady_clock::now();
      const PointCloud cloud = depthToPointCloud(frame.depth, camera, &frame.color, conversion);
      rays->integratePointCloud(T_G_C, cloud);
      run.frame_ms.push_back(
          std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start)
              .count());
    }
  }
  run.blocks = run.layer->numBlocks();
  run.layer_mib = run.layer->memoryBytes() / 1048576.0;
  meshRun(&run);
  return run;
}

#ifdef CBLOX_HAVE_VOXBLOX
// voxblox's FastTsdfIntegrator once on a fresh layer; its TSDF (copied into a cblox layer)
// is meshed like ours. conversion_ms holds depthToPointCloud alone per frame, which our
// fast rows' clock includes and voxblox's does not.
Run integrateVoxblox(const BenchSequence& seq, int threads, int voxels_per_side) {
  VoxbloxResult result = runVoxbloxFastTsdf(seq, kVoxelSize, kTruncation, kMaxDepth, kMaxRayLength,
                                            threads, voxels_per_side);
  Run run;
  run.name = "voxblox fast";
  run.threads = threads;
  run.voxels_per_side = voxels_per_side;
  run.frame_ms = std::move(result.frame_ms);
  run.conversion_ms = std::move(result.conversion_ms);
  run.blocks = result.blocks;
  run.layer_mib = result.layer_mib;  // voxblox's own count: its blocks, no hash map
  run.layer = std::move(result.layer);
  meshRun(&run);
  return run;
}
#endif

// Accuracy against the reference (the simple integrator's TSDF, the fused reference):
// RMSE of |reference TSDF| interpolated at this mesh's vertices, over the vertices where
// the reference is observed (the distance to the reference surface, valid within the
// truncation band), its mean with sign (positive: this surface lies on the sensor's side
// of the reference's, i.e. this TSDF is biased towards "inside"), the share of vertices
// where it is not observed, and the share of reference vertices within one voxel of this
// TSDF's surface.
void compareToReference(const Run& reference, Run* run) {
  const TsdfInterpolator ref(*reference.layer);
  double sum = 0.0, sum_sq = 0.0;
  size_t observed = 0;
  for (const Eigen::Vector3f& v : run->mesh.vertices) {
    float d = 0.0f;
    if (!ref.getInterpolatedDistance(v, &d)) continue;
    sum += d;
    sum_sq += static_cast<double>(d) * d;
    ++observed;
  }
  run->rmse_to_reference_mm = observed == 0 ? 0.0 : 1e3 * std::sqrt(sum_sq / observed);
  run->mean_signed_to_reference_mm = observed == 0 ? 0.0 : 1e3 * sum / observed;
  run->unobserved_in_reference =
      run->mesh.vertices.empty() ? 0.0
                                 : 1.0 - static_cast<double>(observed) / run->mesh.vertices.size();
  const TsdfInterpolator own(*run->layer);
  size_t covered = 0;
  for (const Eigen::Vector3f& v : reference.mesh.vertices) {
    float d = 0.0f;
    covered += own.getInterpolatedDistance(v, &d) && std::abs(d) < kVoxelSize ? 1 : 0;
  }
  run->reference_coverage = reference.mesh.vertices.empty()
                                ? 0.0
                                : static_cast<double>(covered) / reference.mesh.vertices.size();
}

BenchSequence load(const std::string& folder) {
  std::string error;
  auto reader = SevenScenesReader::open(folder, &error);
  if (!reader) throw std::runtime_error(error);
  BenchSequence seq;
  seq.intrinsics = reader->depthIntrinsics();
  for (size_t i = 0; i < reader->size(); ++i) {
    SevenScenesFrame f;
    if (!reader->read(i, &f, &error)) throw std::runtime_error(error);
    seq.frames.push_back({f.T_G_C, std::move(f.depth), std::move(f.color)});
  }
  return seq;
}

}  // namespace
}  // namespace cblox::bench

int main(int argc, char** argv) {
  using namespace cblox::bench;
  std::string data = std::string(CBLOX_SHARED_DATA_DIR) + "/7scenes-rgbd-50";
  std::string json_path;
  size_t simple_frames = 50;
  int repeats = 3;
  std::string only;  // run one integrator (2 threads, 8^3) for its peak memory
  CLI::App app{
      "cblox-bench-integrators: ms per frame of the simple, fast and projective integrators on\n"
      "7-Scenes frames (and Open3D's ScalableTSDFVolume and voxblox's fast integrator when\n"
      "built with them), mesh time and accuracy against the simple integrator's TSDF.",
      "cblox-bench-integrators"};
  app.add_option("--data", data, "7-Scenes folder")->capture_default_str();
  app.add_option("--simple-frames", simple_frames, "frames of the (slow) simple integrator")
      ->capture_default_str();
  app.add_option("--repeats", repeats, "runs per configuration (the fastest per frame counts)")
      ->capture_default_str();
  app.add_option("--json", json_path, "also write the figures as JSON")->type_name("FILE");
  app.add_option("--only", only,
                 "simple | fast | projective | open3d | voxblox: one integrator (2 threads,\n"
                 "8^3 blocks) for its peak memory");
  if (const std::optional<int> code = cblox::parseCommandLine(app, argc, argv)) return *code;
  repeats = std::max(1, repeats);
  BenchSequence seq;
  try {
    seq = load(data);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "cannot load %s: %s\n", data.c_str(), e.what());
    return 1;
  }
  std::printf("%zu frames %dx%d from %s; voxel %.3f m, truncation %.3f m, max depth %.1f m\n",
              seq.frames.size(), seq.intrinsics.width, seq.intrinsics.height, data.c_str(),
              kVoxelSize, kTruncation, kMaxDepth);

  if (!only.empty()) {
    // Peak memory of one integrator: the process's peak RSS minus its RSS once the frames
    // are loaded (the kernel reports peaks only, so one integrator per process).
    const double loaded_mib = peakRssMiB();
    size_t blocks = 0;
    double layer_mib = 0.0;
    if (only == "open3d") {
#ifdef CBLOX_HAVE_OPEN3D
      runOpen3dScalableTsdf(seq, kVoxelSize, kTruncation, kMaxDepth, 2);
#else
      std::fprintf(stderr, "built without the Open3D peer\n");
      return kExitNoOpen3d;
#endif
    } else if (only == "voxblox") {
#ifdef CBLOX_HAVE_VOXBLOX
      const VoxbloxResult peer = runVoxbloxFastTsdf(seq, kVoxelSize, kTruncation, kMaxDepth,
                                                    kMaxRayLength, 2, 8, /*copy_layer=*/false);
      blocks = peer.blocks;
      layer_mib = peer.layer_mib;
#else
      std::fprintf(stderr, "built without the voxblox peer\n");
      return kExitNoVoxblox;
#endif
    } else if (only == "simple" || only == "fast" || only == "projective") {
      const Kind kind = only == "simple" ? Kind::kSimple
                        : only == "fast" ? Kind::kFast
                                         : Kind::kProjective;
      const Run run = integrateOnce(seq, kind, 2, 8, seq.frames.size(), FastVariant{});
      blocks = run.blocks;
      layer_mib = run.layer_mib;
    } else {
      std::fprintf(stderr, "--only takes simple, fast, projective, open3d or voxblox, got '%s'\n",
                   only.c_str());
      return 2;
    }
    std::printf("%s: peak RSS %.0f MiB, %.0f MiB above the loaded frames", only.c_str(),
                peakRssMiB(), peakRssMiB() - loaded_mib);
    if (only != "open3d") std::printf("; %zu blocks, layer %.1f MiB", blocks, layer_mib);
    std::printf("\n");
    return 0;
  }

  // Every configuration runs once per round, in `repeats` rounds (the simple rows, the
  // reference, in the first only), and keeps per frame its fastest round. The host's speed
  // drifts over minutes, so the peers run in the same rounds as ours, seconds apart: a slow
  // spell slows both, and the ratios hold where the absolute times do not.
  struct Job {
    std::string label;
    int rounds;
    std::function<Run()> once;
  };
  std::vector<Job> jobs;
  auto add = [&](Kind kind, int threads, int vps, size_t frames, int rounds,
                 const FastVariant& variant = FastVariant{}) {
    char label[96];
    std::snprintf(label, sizeof(label), "%s, %d thread(s), %d^3 blocks", kindName(kind), threads,
                  vps);
    jobs.push_back({label, rounds, [&seq, kind, threads, vps, frames, variant] {
                      return integrateOnce(seq, kind, threads, vps, frames, variant);
                    }});
  };
  add(Kind::kSimple, 2, 8, simple_frames, 1);
  add(Kind::kSimple, 1, 8, std::min<size_t>(simple_frames, 10), 1);
  for (int threads : {1, 2}) add(Kind::kFast, threads, 8, seq.frames.size(), repeats);
  add(Kind::kFast, 2, 16, seq.frames.size(), repeats);
  add(Kind::kFast, 2, 8, seq.frames.size(), repeats,
      {.visited = cblox::VisitedVoxelSet::kApproxHashSet});
  // voxblox's default start cells (half a voxel), the default until commit d354c6c.
  add(Kind::kFast, 2, 8, seq.frames.size(), repeats, {.start_voxel_subsampling_factor = 2.0f});
  for (int threads : {1, 2}) add(Kind::kProjective, threads, 8, seq.frames.size(), repeats);
  add(Kind::kProjective, 2, 16, seq.frames.size(), repeats);
  add(Kind::kProjectivePortable, 1, 8, seq.frames.size(), repeats);
#ifdef CBLOX_HAVE_OPEN3D
  // Right after our projective rows, the peer of their ratios.
  for (int threads : {1, 2}) {
    jobs.push_back({"Open3D ScalableTSDFVolume, " + std::to_string(threads) + " thread(s)", repeats,
                    [&seq, threads] {
                      Open3dResult peer =
                          runOpen3dScalableTsdf(seq, kVoxelSize, kTruncation, kMaxDepth, threads);
                      Run run;
                      run.name = "Open3D ScalableTSDFVolume";
                      run.threads = threads;
                      run.voxels_per_side = 16;
                      run.frame_ms = std::move(peer.frame_ms);
                      run.mesh_vertices = peer.mesh_vertices;
                      return run;
                    }});
  }
#endif
#ifdef CBLOX_HAVE_VOXBLOX
  // voxblox's FastTsdfIntegrator beside our fast rows: 1 and 2 threads with 8^3 blocks, and
  // 2 threads with 16^3 (voxblox_ros's default block size) beside ours with 16^3.
  for (const auto& [threads, vps] : {std::pair{1, 8}, std::pair{2, 8}, std::pair{2, 16}}) {
    jobs.push_back({"voxblox fast, " + std::to_string(threads) + " thread(s), " +
                        std::to_string(vps) + "^3 blocks",
                    repeats, [&seq, threads = threads, vps = vps] {
                      return integrateVoxblox(seq, threads, vps);
                    }});
  }
#endif
  std::vector<Run> all(jobs.size());
  for (int round = 0; round < repeats; ++round) {
    for (size_t j = 0; j < jobs.size(); ++j) {
      if (round >= jobs[j].rounds) continue;
      std::printf("round %d of %d: %s ...\n", round + 1, repeats, jobs[j].label.c_str());
      std::fflush(stdout);
      Run run = jobs[j].once();
      if (round == 0) {
        all[j] = std::move(run);
      } else {
        keepFastest(&all[j], run);
      }
    }
  }
  // Ours and voxblox's in `runs`, Open3D's (no layer) apart.
  std::vector<Run> runs, open3d_runs;
  for (Run& run : all) {
    (run.name.rfind("Open3D", 0) == 0 ? open3d_runs : runs).push_back(std::move(run));
  }
  const bool reference_complete = simple_frames >= seq.frames.size();
  for (size_t i = 2; i < runs.size() && reference_complete; ++i)
    compareToReference(runs[0], &runs[i]);

  auto optional = [](double value, double scale, const char* unit) {
    if (value < 0) return std::string("-");
    char text[32];
    std::snprintf(text, sizeof(text), "%.1f%s", value * scale, unit);
    return std::string(text);
  };
  std::printf(
      "\n| integrator | threads | block | median ms/frame | p95 ms | blocks | layer MiB | "
      "mesh ms | mesh vertices | RMSE to simple | mean to simple, signed | "
      "vertices outside simple | covers simple |\n");
  std::printf("|---|---|---|---|---|---|---|---|---|---|---|---|---|\n");
  for (const Run& run : runs) {
    char signed_mean[32] = "-";  // only where the RMSE is measured
    if (run.rmse_to_reference_mm >= 0) {
      std::snprintf(signed_mean, sizeof(signed_mean), "%+.1f mm", run.mean_signed_to_reference_mm);
    }
    std::printf("| %s | %d | %d^3 | %.2f | %.2f | %zu | %.1f | %.1f | %zu | %s | %s | %s | %s |\n",
                run.name.c_str(), run.threads, run.voxels_per_side, median(run.frame_ms),
                percentile(run.frame_ms, 0.95), run.blocks, run.layer_mib, run.mesh_ms,
                run.mesh_vertices, optional(run.rmse_to_reference_mm, 1.0, " mm").c_str(),
                signed_mean, optional(run.unobserved_in_reference, 100.0, "%").c_str(),
                optional(run.reference_coverage, 100.0, "%").c_str());
  }
  // Ratios of median ms per frame, all measured in this run: {row, threads, block, peer,
  // ratio}. A peer that is not built gives no ratio (the targets are ratios).
  struct Ratio {
    std::string integrator;
    int threads;
    int voxels_per_side;
    std::string peer;
    double ratio;
  };
  std::vector<Ratio> ratios;
  nlohmann::ordered_json open3d_json = nlohmann::ordered_json::array();
#ifdef CBLOX_HAVE_OPEN3D
  std::vector<std::pair<int, double>> open3d_medians;
  for (const Run& peer : open3d_runs) {
    open3d_medians.emplace_back(peer.threads, median(peer.frame_ms));
    open3d_json.push_back({{"integrator", peer.name},
                           {"threads", peer.threads},
                           {"voxels_per_side", 16},
                           {"median_ms", median(peer.frame_ms)},
                           {"p95_ms", percentile(peer.frame_ms, 0.95)},
                           {"mesh_vertices", peer.mesh_vertices}});
    std::printf("| %s | %d | 16^3 | %.2f | %.2f | - | - | - | %zu | - | - | - | - |\n",
                peer.name.c_str(), peer.threads, median(peer.frame_ms),
                percentile(peer.frame_ms, 0.95), peer.mesh_vertices);
  }
  std::printf(
      "\nratios to Open3D (median ms per frame, same threads, same run; the voxblox rows are "
      "voxblox / Open3D):\n");
  for (const Run& run : runs) {
    if (run.voxels_per_side != 8 || run.name.rfind("simple", 0) == 0 ||
        run.name.find("hash") != std::string::npos) {
      continue;
    }
    for (const auto& [threads, o3d] : open3d_medians) {
      if (threads == run.threads) {
        const double ratio = median(run.frame_ms) / o3d;
        ratios.push_back({run.name, threads, run.voxels_per_side, "Open3D", ratio});
        std::printf("  %s / Open3D, %d thread(s): %.2f\n", run.name.c_str(), threads, ratio);
      }
    }
  }
#else
  std::printf(
      "\nno ratio to Open3D: the Open3D peer is not built (install libopen3d-dev: "
      "scripts/setup.sh --bench, then rebuild)\n");
#endif
#ifdef CBLOX_HAVE_VOXBLOX
  double conversion_ms = 0.0;
  for (const Run& run : runs) {
    if (!run.conversion_ms.empty()) conversion_ms = median(run.conversion_ms);
  }
  std::printf(
      "\nratios to voxblox's fast integrator (median ms per frame, same threads, same block "
      "size, same run):\n");
  for (const Run& run : runs) {
    if (run.name != "fast" && run.name != "projective") continue;
    for (const Run& peer : runs) {
      if (peer.name == "voxblox fast" && peer.threads == run.threads &&
          peer.voxels_per_side == run.voxels_per_side) {
        const double ratio = median(run.frame_ms) / median(peer.frame_ms);
        ratios.push_back({run.name, run.threads, run.voxels_per_side, "voxblox fast", ratio});
        std::printf("  %s / voxblox fast, %d thread(s), %d^3: %.2f (voxblox %.1fx slower)\n",
                    run.name.c_str(), run.threads, run.voxels_per_side, ratio, 1.0 / ratio);
      }
    }
  }
  std::printf(
      "  (our fast rows' clock includes the depth -> point cloud conversion, %.2f ms median "
      "per frame; voxblox's clock is integratePointCloud alone)\n",
      conversion_ms);
#else
  std::printf(
      "\nno ratio to voxblox: the voxblox peer is not built (it needs a build of voxblox's "
      "core: see test/bench/CMakeLists.txt, CBLOX_VOXBLOX_ROOT)\n");
#endif
  std::printf("\npeak RSS of the whole benchmark process: %.0f MiB\n", peakRssMiB());
  if (!json_path.empty()) {
    nlohmann::ordered_json json = {{"runs", nlohmann::ordered_json::array()},
                                   {"open3d", open3d_json},
                                   {"ratios", nlohmann::ordered_json::array()}};
    for (const Run& r : runs) {
      json["runs"].push_back({{"integrator", r.name},
                              {"threads", r.threads},
                              {"voxels_per_side", r.voxels_per_side},
                              {"median_ms", median(r.frame_ms)},
                              {"p95_ms", percentile(r.frame_ms, 0.95)},
                              {"blocks", r.blocks},
                              {"layer_mib", r.layer_mib},
                              {"mesh_ms", r.mesh_ms},
                              {"mesh_vertices", r.mesh_vertices},
                              {"rmse_to_simple_mm", r.rmse_to_reference_mm},
                              {"mean_signed_to_simple_mm", r.mean_signed_to_reference_mm},
                              {"outside_simple", r.unobserved_in_reference},
                              {"covers_simple", r.reference_coverage}});
    }
    for (const Ratio& r : ratios) {
      json["ratios"].push_back({{"integrator", r.integrator},
                                {"threads", r.threads},
                                {"voxels_per_side", r.voxels_per_side},
                                {"over", r.peer},
                                {"ratio", r.ratio}});
    }
    std::ofstream(json_path) << json.dump() << "\n";
  }
  bool have_open3d = false, have_voxblox = false;
#ifdef CBLOX_HAVE_OPEN3D
  have_open3d = true;
#endif
#ifdef CBLOX_HAVE_VOXBLOX
  have_voxblox = true;
#endif
  if (!have_open3d || !have_voxblox) {
    const int code = !have_open3d && !have_voxblox ? kExitNoPeers
                     : !have_open3d                ? kExitNoOpen3d
                                                   : kExitNoVoxblox;
    std::fprintf(stderr, "cblox-bench-integrators: %s missing (exit %d)\n",
                 code == kExitNoPeers    ? "the Open3D and voxblox peers are"
                 : code == kExitNoOpen3d ? "the Open3D peer is"
                                         : "the voxblox peer is",
                 code);
    return code;
  }
  return 0;
}
