// cblox-integrate: integrates a depth source into one TSDF volume and writes a PLY mesh.
//
//   cblox-integrate --config config/integrate.yaml --source sim:room --output room.ply
//   cblox-integrate --source 7scenes:../shared/data/7scenes-rgbd-50 --integrator projective
//
// Sources: any capture source with depth (drivers/open_frame_source.h: sim:room|hall|town|
// MESH, tum:DIR, 7scenes:DIR) and "synthetic-room" (the analytic room of the unit tests).
// Simulated sources have an exact ground-truth mesh: the reconstruction's accuracy and
// completeness against it are printed. Exit status 0 on success, 1 on a runtime error,
// 2 on a usage or configuration error.

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "core/eval/mesh_accuracy.h"
#include "core/integrator/make_integrator.h"
#include "core/io/ply_io.h"
#include "core/mesh/mesh_integrator.h"
#include "core/raycast/triangle_mesh_raycaster.h"
#include "core/tsdf/tsdf_layer.h"
#include "daemon/capture/capture_config.h"
#include "daemon/common/cli.h"
#include "daemon/common/run_loop.h"
#include "daemon/common/yaml_config.h"
#include "drivers/open_frame_source.h"
#include "drivers/synthetic/demo_room_orbit.h"
#include "drivers/synthetic/synthetic_frame_source.h"

namespace cblox {
namespace {

using Clock = std::chrono::steady_clock;

struct Options {
  std::string config_file;
  std::string source = "sim:room";
  std::string output = "out/mesh.ply";
  std::optional<std::string> integrator;
  std::optional<int> frames;
  std::string trajectory = "orbit";
  std::string noise = "none";
  std::string ground_truth_output;
  bool ascii = false;
};

/// One depth frame from any source.
struct Frame {
  Transformationd T_G_C;
  DepthImage depth;
  ColorImage color;
};

/// The built-in synthetic room source's settings (YAML section `synthetic`).
DemoRoomOrbit loadSyntheticSettings(const YAML::Node& node) {
  requireKnownKeys(node, "synthetic",
                   {"width", "height", "fx", "fy", "frames", "rate_hz", "orbit_radius_m",
                    "orbit_height_m", "look_at_height_m", "max_range_m"});
  DemoRoomOrbit s;
  if (isAbsent(node)) return s;
  readOptional(node, "synthetic", "width", &s.width);
  readOptional(node, "synthetic", "height", &s.height);
  readOptional(node, "synthetic", "fx", &s.fx);
  readOptional(node, "synthetic", "fy", &s.fy);
  readOptional(node, "synthetic", "frames", &s.frames);
  readOptional(node, "synthetic", "rate_hz", &s.rate_hz);
  readOptional(node, "synthetic", "orbit_radius_m", &s.orbit_radius_m);
  readOptional(node, "synthetic", "orbit_height_m", &s.orbit_height_m);
  readOptional(node, "synthetic", "look_at_height_m", &s.look_at_height_m);
  readOptional(node, "synthetic", "max_range_m", &s.max_range_m);
  if (s.frames < 1) throw ConfigError("synthetic.frames: must be >= 1");
  return s;
}

/// A source yields frames until it returns false.
struct Source {
  PinholeIntrinsics intrinsics;
  size_t size = 0;
  std::function<bool(Frame*)> next;
  std::optional<AnalyticScene> ground_truth;             // analytic sources
  std::shared_ptr<const Mesh> ground_truth_mesh;          // simulated sources
};

Source openSource(const Options& options, const YAML::Node& root) {
  Source source;
  if (options.source == "synthetic-room") {
    DemoRoomOrbit s = loadSyntheticSettings(root["synthetic"]);
    s.frames = options.frames.value_or(s.frames);
    source.intrinsics = s.intrinsics();
    auto synthetic = std::make_shared<SyntheticDepthSource>(s.source());
    source.ground_truth = synthetic->scene();
    source.size = synthetic->size();
    source.next = [synthetic](Frame* frame) {
      SyntheticFrame f;
      if (!synthetic->next(&f)) return false;
      frame->T_G_C = f.T_G_C;
      frame->depth = std::move(f.depth);
      frame->color = std::move(f.color);
      return true;
    };
    return source;
  }
  SourceConfig source_config;
  source_config.trajectory = options.trajectory;
  source_config.sim.noise = sensorNoisePreset(options.noise);
  if (options.frames) {
    if (*options.frames < 1) throw ConfigError("--frames must be >= 1");
    source_config.max_frames = static_cast<size_t>(*options.frames);
  }
  std::string error;
  std::shared_ptr<FrameSource> frames = openFrameSource(options.source, source_config, &error);
  if (frames == nullptr) throw ConfigError(error);
  const SourceInfo& info = frames->info();
  if (!info.depth_intrinsics) {
    throw ConfigError("source " + info.name + " delivers no depth images (stereo only)");
  }
  for (const std::string& note : info.notes) std::printf("source note: %s\n", note.c_str());
  source.intrinsics = *info.depth_intrinsics;
  source.size = info.frame_count.value_or(0);
  if (options.source.rfind("sim:", 0) == 0) {
    source.ground_truth_mesh = loadSimSceneMesh(options.source, &error);
  }
  const Transformationd T_C_D = info.T_C_D;
  source.next = [frames, T_C_D](Frame* frame) {
    CaptureFrame capture;
    std::string read_error;
    while (true) {
      const FrameSource::Status status = frames->next(&capture, &read_error);
      if (status == FrameSource::Status::kEnd) return false;
      if (status == FrameSource::Status::kError) {
        std::fprintf(stderr, "cblox-integrate: frame skipped: %s\n", read_error.c_str());
        continue;
      }
      if (!capture.T_G_C) {
        std::fprintf(stderr, "cblox-integrate: frame %lld has no pose, skipped\n",
                     static_cast<long long>(capture.frame_id));
        continue;
      }
      frame->T_G_C = *capture.T_G_C * T_C_D;  // the depth camera's pose
      frame->depth = std::move(capture.depth);
      frame->color = std::move(capture.color);
      return true;
    }
  };
  return source;
}

double percentile(std::vector<double> values, double q) {
  if (values.empty()) return 0.0;
  std::sort(values.begin(), values.end());
  const size_t i = std::min(values.size() - 1, static_cast<size_t>(q * (values.size() - 1) + 0.5));
  return values[i];
}

int run(const Options& options) {
  const YAML::Node root =
      options.config_file.empty() ? YAML::Node() : loadYamlFile(options.config_file);
  requireKnownKeys(root, options.config_file.empty() ? "config" : options.config_file,
                   {"layer", "integrator", "mesh", "output", "synthetic"});
  const LayerConfig layer_config = loadLayerConfig(root["layer"]);
  IntegratorType type = IntegratorType::kFast;
  const IntegratorConfig integrator_config =
      loadIntegratorConfig(root["integrator"], layer_config.voxel_size, &type);
  if (options.integrator) type = parseIntegratorType(*options.integrator);
  const MeshConfig mesh_config = loadMeshConfig(root["mesh"]);
  bool connected = true;
  std::string format = options.ascii ? "ascii" : "binary";
  requireKnownKeys(root["output"], "output", {"connected", "format"});
  if (!isAbsent(root["output"])) {
    readOptional(root["output"], "output", "connected", &connected);
    if (!options.ascii) readOptional(root["output"], "output", "format", &format);
  }
  if (format != "binary" && format != "ascii") {
    throw ConfigError("output.format: must be binary or ascii, got '" + format + "'");
  }

  Source source = openSource(options, root);
  const PinholeCamera camera(source.intrinsics);
  TsdfLayer layer(layer_config);
  const std::unique_ptr<DepthIntegrator> integrator =
      makeIntegrator(type, integrator_config, &layer);
  std::printf(
      "cblox-integrate: source %s (%zu frames, %dx%d), %s integrator, voxel %.3f m, "
      "truncation %.3f m, %d threads\n",
      options.source.c_str(), source.size, source.intrinsics.width, source.intrinsics.height,
      integratorTypeName(type), layer_config.voxel_size, integrator_config.truncation_distance_m,
      integrator_config.num_threads);

  std::vector<double> frame_ms;
  size_t frames = 0, skipped_points = 0;
  const auto start = Clock::now();
  Frame frame;
  while (source.next(&frame)) {
    const Transformation T_G_C = frame.T_G_C.cast<float>();
    const ColorImage* color = frame.color.empty() ? nullptr : &frame.color;
    const IntegrationStats stats = integrator->integrateDepthImage(T_G_C, frame.depth, camera, color);
    frame_ms.push_back(stats.seconds * 1e3);
    skipped_points += stats.points_invalid + stats.points_out_of_range;
    ++frames;
    if (frames % 10 == 0 || frames == source.size) {
      const double elapsed = std::chrono::duration<double>(Clock::now() - start).count();
      const double rate = frames / elapsed;
      std::printf("  frame %zu/%zu  %.1f frames/s  integration %.1f ms  blocks %zu  ETA %.0f s\n",
                  frames, source.size, rate, frame_ms.back(), layer.numBlocks(),
                  (source.size - frames) / rate);
      std::fflush(stdout);
    }
  }
  std::printf(
      "integrated %zu frames: median %.2f ms, p95 %.2f ms per frame; %zu blocks, "
      "%.1f MiB\n",
      frames, percentile(frame_ms, 0.5), percentile(frame_ms, 0.95), layer.numBlocks(),
      layer.memoryBytes() / 1048576.0);

  const auto mesh_start = Clock::now();
  MeshIntegrator mesher(layer, mesh_config);
  mesher.update(false, true);
  const Mesh mesh = mesher.extractMesh(connected);
  const double mesh_ms =
      std::chrono::duration<double, std::milli>(Clock::now() - mesh_start).count();
  std::string error;
  if (!writePly(options.output, mesh,
                format == "ascii" ? PlyFormat::kAscii : PlyFormat::kBinaryLittleEndian, &error)) {
    std::fprintf(stderr, "cblox-integrate: %s\n", error.c_str());
    return 1;
  }
  std::printf("mesh: %zu vertices, %zu triangles in %.1f ms -> %s\n", mesh.numVertices(),
              mesh.numTriangles(), mesh_ms, options.output.c_str());
  if (source.ground_truth) {
    std::vector<double> errors;
    errors.reserve(mesh.numVertices());
    double sum_sq = 0.0;
    for (const Eigen::Vector3f& v : mesh.vertices) {
      errors.push_back(std::abs(source.ground_truth->signedDistance(v.cast<double>())));
      sum_sq += errors.back() * errors.back();
    }
    const double rmse = errors.empty() ? 0.0 : std::sqrt(sum_sq / errors.size());
    const double within_voxel =
        errors.empty() ? 0.0 : std::count_if(errors.begin(), errors.end(), [&](double e) {
                                 return e <= layer_config.voxel_size;
                               }) / static_cast<double>(errors.size());
    std::printf(
        "accuracy vs ground truth: vertex RMSE %.2f mm, median %.2f mm, p90 %.2f mm, "
        "max %.2f mm, %.2f%% within one voxel\n",
        rmse * 1e3, percentile(errors, 0.5) * 1e3, percentile(errors, 0.9) * 1e3,
        percentile(errors, 1.0) * 1e3, 100.0 * within_voxel);
  }
  if (source.ground_truth_mesh) {
    const auto raycaster = TriangleMeshRaycaster::create(*source.ground_truth_mesh, &error);
    if (raycaster == nullptr) throw std::runtime_error(error);
    MeshAccuracyConfig accuracy_options;
    accuracy_options.completeness_threshold_m = 2.0 * layer_config.voxel_size;
    const auto accuracy = evaluateMeshAccuracy(*raycaster, mesh, accuracy_options, &error);
    if (!accuracy) throw std::runtime_error(error);
    const ErrorStatistics& a = accuracy->accuracy_m;
    std::printf(
        "accuracy vs ground truth: vertex RMSE %.2f mm, median %.2f mm, p90 %.2f mm, "
        "max %.2f mm; completeness %.1f%% of the scene surface within %.0f mm\n",
        a.rmse * 1e3, a.median * 1e3, a.p90 * 1e3, a.max * 1e3, 100.0 * accuracy->completeness,
        accuracy_options.completeness_threshold_m * 1e3);
    if (!options.ground_truth_output.empty()) {
      if (!writePly(options.ground_truth_output, *source.ground_truth_mesh,
                    PlyFormat::kBinaryLittleEndian, &error)) {
        std::fprintf(stderr, "cblox-integrate: %s\n", error.c_str());
        return 1;
      }
      std::printf("ground-truth mesh -> %s\n", options.ground_truth_output.c_str());
    }
  } else if (!options.ground_truth_output.empty()) {
    throw ConfigError("--write-ground-truth needs a sim: source");
  }
  if (skipped_points > 0)
    std::printf("skipped %zu invalid or out-of-range depth pixels\n", skipped_points);
  return mesh.numVertices() > 0 ? 0 : 1;
}

}  // namespace
}  // namespace cblox

int main(int argc, char** argv) {
  cblox::Options options;
  CLI::App app{
      "cblox-integrate: integrates a depth source into one TSDF volume and writes a PLY mesh;\n"
      "for simulated sources also the accuracy and completeness against the exact scene.\n"
      "Exit status: 0 success, 1 runtime error, 2 usage or configuration error.",
      "cblox-integrate"};
  app.add_option("--config", options.config_file, "settings (YAML, as config/integrate.yaml)")
      ->type_name("FILE");
  app.add_option("--source", options.source,
                 "sim:room|hall|town|MESH.ply, tum:DIR, 7scenes:DIR, synthetic-room (analytic)")
      ->type_name("SPEC")
      ->capture_default_str();
  app.add_option("--frames", options.frames, "frames to integrate at the most")->type_name("N");
  app.add_option("--integrator", options.integrator,
                 "fast | simple | projective (default: the settings')")
      ->type_name("KIND");
  app.add_option("--trajectory", options.trajectory,
                 "orbit | loop | lawnmower | figure-eight, or a TUM file")
      ->type_name("KIND|FILE")
      ->capture_default_str();
  app.add_option("--noise", options.noise, "none | realistic")
      ->type_name("PRESET")
      ->capture_default_str();
  app.add_option("--output", options.output, "the mesh")
      ->type_name("FILE.ply")
      ->capture_default_str();
  app.add_option("--write-ground-truth", options.ground_truth_output,
                 "also write the exact scene mesh (sim: sources)")
      ->type_name("FILE.ply");
  app.add_flag("--ascii", options.ascii, "ASCII PLY instead of binary");
  if (const std::optional<int> code = cblox::parseCommandLine(app, argc, argv)) return *code;
  return cblox::runProcess("cblox-integrate", [&] { return cblox::run(options); });
}
