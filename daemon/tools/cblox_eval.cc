// cblox-eval: accuracy of a reconstruction against ground truth (mesh and/or trajectory).
//
//   cblox-eval --gt-mesh room_gt.ply --mesh room.ply --json eval.json --error-png error.png
//   cblox-eval --gt-trajectory gt.txt --trajectory est.txt --align se3 --trajectory-png traj.png
//   cblox-eval --mesh street.ply --height-png street.png --up -y    # no ground truth needed
//
// Mesh part (both meshes given): accuracy of the reconstruction's vertices against the
// ground-truth surface, completeness of the ground truth, and the surface block count
// (evaluateMeshAccuracy(), countSurfaceBlocks()). Trajectory part (both trajectories given,
// TUM format): ATE after alignment and RPE (evaluateTrajectory()). When both parts run and
// the alignment is not "none", the trajectory's alignment T_G_E is applied to the
// reconstruction first (it was built in the estimate's frame E); --no-mesh-align turns that
// off. Prints a summary (mesh errors in mm) and writes one JSON object with the sections
// "inputs", "mesh", "map" and "trajectory" (null when a part did not run).
// --height-png renders the reconstruction coloured by height (--up: which axis of its frame
// points up; -y for a camera's frame) and needs no ground truth.
// Exit status 0 on success, 1 when an evaluation or an output fails, 2 on a usage error or an
// input that cannot be read.

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <limits>
#include <memory>
#include <optional>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

#include <CLI/CLI.hpp>
#include <nlohmann/json.hpp>

#include "core/eval/mesh_accuracy.h"
#include "core/eval/mesh_error_render.h"
#include "core/eval/mesh_height.h"
#include "core/eval/trajectory_metrics.h"
#include "core/eval/trajectory_plot.h"
#include "core/io/obj_io.h"
#include "core/io/ply_io.h"
#include "core/io/tum_trajectory.h"
#include "core/raycast/triangle_mesh_raycaster.h"
#include "daemon/common/cli.h"

namespace cblox {
namespace {

constexpr int kExitFailure = 1;
constexpr int kExitUsage = 2;

/// A usage error or an unreadable input: exit status 2.
struct UsageError : std::runtime_error {
  using std::runtime_error::runtime_error;
};

/// An evaluation or output failure: exit status 1.
struct EvaluationError : std::runtime_error {
  using std::runtime_error::runtime_error;
};

struct Options {
  std::string gt_mesh;
  std::string mesh;
  std::string gt_trajectory;
  std::string trajectory;
  AlignmentType alignment = AlignmentType::kSE3;
  bool mesh_align = true;
  double threshold_m = 0.05;
  double sample_spacing_m = 0.02;
  double max_distance_m = std::numeric_limits<double>::infinity();
  double max_time_difference_s = 0.02;
  int rpe_delta_frames = 1;
  double voxel_size_m = 0.02;
  int block_voxels = 8;
  std::optional<size_t> map_blocks;
  std::optional<size_t> map_bytes;
  std::string json;
  std::string error_png;
  std::string trajectory_png;
  std::string height_png;
  Eigen::Vector3d up = Eigen::Vector3d::UnitZ();
  std::optional<MeshViewpoint> view;
  double max_error_m = 0.05;
  int threads = 2;
};

constexpr const char* kFooter =
    R"(Mesh accuracy (needs --gt-mesh and --mesh; PLY or Wavefront OBJ, by file extension):
  accuracy       distance of every reconstructed vertex to the closest point of the
                 ground-truth triangles: RMSE, mean, median, p90, max (printed in mm)
  completeness   share of ground-truth surface samples (area-uniform, one per
                 --sample-spacing^2) within --threshold metres of the reconstruction's
                 triangles (of its vertices for a point cloud); also precision (share of
                 vertices within --threshold) and F-score
Trajectory accuracy (needs --gt-trajectory and --trajectory, TUM format
  "t tx ty tz qx qy qz qw"): poses associated by time (nearest within
  --max-time-difference seconds), ATE RMSE after --align (sim3 for a scale-free
  estimate), RPE over --rpe-delta frames.
  When both parts run and --align is not none, the trajectory's alignment (estimate
  frame -> ground-truth frame) is applied to the reconstruction before the mesh is
  evaluated, as for a map built with estimated poses; --no-mesh-align keeps the
  reconstruction as it is (e.g. built with ground-truth poses).
Map size:
  surface blocks  number of blocks of a voxel grid (--voxel-size metres, --block-voxels
                  per side, laid out as the TSDF layer does) that contain a reconstructed
                  vertex, and their voxel bytes (12 bytes per voxel). A lower bound of the
                  blocks a TSDF map at that resolution allocated for this mesh, not the
                  map's true size (it also holds the truncation band and free space).
Exit status: 0 success, 1 evaluation or output failed, 2 usage error or unreadable input.)";

// "--view eye_x,eye_y,eye_z,at_x,at_y,at_z"; throws CLI::ValidationError (a usage error).
MeshViewpoint parseView(const std::string& text) {
  std::vector<double> values;
  std::stringstream stream(text);
  std::string item;
  while (std::getline(stream, item, ',')) {
    const std::optional<double> value = parseFiniteNumber(item);
    if (!value) throw CLI::ValidationError("--view", "needs finite numbers, got '" + item + "'");
    values.push_back(*value);
  }
  if (values.size() != 6) {
    throw CLI::ValidationError(
        "--view",
        "needs 6 comma-separated numbers eye_x,eye_y,eye_z,at_x,at_y,at_z, got '" + text + "'");
  }
  MeshViewpoint view{Eigen::Vector3d(values[0], values[1], values[2]),
                     Eigen::Vector3d(values[3], values[4], values[5])};
  if ((view.eye - view.look_at).norm() <= 0.0) {
    throw CLI::ValidationError("--view", "the eye and the look-at point coincide");
  }
  return view;
}

/// The options of the command line, written into *options when it is parsed.
void addOptions(CLI::App& app, Options* options) {
  const auto file = [&](const char* name, std::string* value, const char* what) {
    app.add_option(name, *value, what)->type_name("FILE");
  };
  const auto positive = [&](const char* name, auto* value, const char* what) {
    return app.add_option(name, *value, what)
        ->check(finiteNumber(NumberBound::kPositive))
        ->capture_default_str();
  };
  file("--gt-mesh", &options->gt_mesh, "ground-truth mesh (.ply or .obj)");
  file("--mesh", &options->mesh, "the reconstruction (.ply or .obj)");
  file("--gt-trajectory", &options->gt_trajectory, "ground-truth trajectory (TUM)");
  file("--trajectory", &options->trajectory, "estimated trajectory (TUM)");
  app.add_option_function<std::string>(
         "--align",
         [options](const std::string& name) {
           const std::optional<AlignmentType> type = parseAlignmentType(name);
           if (!type) {
             throw CLI::ValidationError("--align", "must be none, se3 or sim3, got '" + name + "'");
           }
           options->alignment = *type;
         },
         "trajectory alignment: none | se3 | sim3 (default se3)")
      ->type_name("KIND");
  app.add_flag_callback(
      "--no-mesh-align", [options] { options->mesh_align = false; },
      "do not apply the trajectory's alignment to the reconstruction");
  positive("--threshold", &options->threshold_m, "completeness distance, metres");
  positive("--sample-spacing", &options->sample_spacing_m,
           "spacing of the ground-truth surface samples, metres");
  app.add_option("--max-distance", options->max_distance_m,
                 "vertices farther than this (metres) from the ground truth are outliers, left\n"
                 "out of the accuracy statistics (default: none)")
      ->check(finiteNumber(NumberBound::kPositive))
      ->type_name("M");
  app.add_option("--max-time-difference", options->max_time_difference_s,
                 "association of poses by time, seconds")
      ->check(finiteNumber(NumberBound::kNonNegative))
      ->capture_default_str();
  positive("--rpe-delta", &options->rpe_delta_frames, "RPE over this many frames");
  positive("--voxel-size", &options->voxel_size_m, "surface blocks: voxel size, metres");
  positive("--block-voxels", &options->block_voxels, "surface blocks: voxels per block side");
  const auto reported = [&](const char* name, std::optional<size_t>* value, const char* what) {
    app.add_option(name, *value,
                   std::string("the map's true ") + what +
                       " as the mapper reported it (copied into the JSON)")
        ->check(finiteNumber(NumberBound::kNonNegative))
        ->type_name("N");
  };
  reported("--map-blocks", &options->map_blocks, "block count");
  reported("--map-bytes", &options->map_bytes, "size in bytes");
  app.add_option("--json", options->json,
                 "one JSON object: \"inputs\", \"mesh\", \"map\", \"trajectory\"")
      ->type_name("FILE");
  app.add_option("--error-png", options->error_png,
                 "the (aligned) reconstruction coloured by vertex error (0 .. --max-error\n"
                 "metres, viridis, colour bar in mm), 1024x768")
      ->type_name("FILE");
  app.add_option("--trajectory-png", options->trajectory_png,
                 "top view of the ground truth and the aligned estimate")
      ->type_name("FILE");
  app.add_option("--height-png", options->height_png,
                 "the reconstruction coloured by height above its lowest vertex (0 .. its\n"
                 "99th percentile, metres), seen from above and to the side, 1024x768; needs\n"
                 "only --mesh")
      ->type_name("FILE");
  app.add_option_function<std::string>(
         "--up",
         [options](const std::string& text) {
           const std::optional<Eigen::Vector3d> up = parseUpAxis(text);
           if (!up) throw CLI::ValidationError("--up", "must be x, y, z, -x, -y or -z");
           options->up = *up;
         },
         "height picture: the axis of the mesh's frame that points up (default z; -y for a\n"
         "camera's frame, as the tracker's G when its first frame is the origin)")
      ->type_name("AXIS");
  app.add_option_function<std::string>(
         "--view", [options](const std::string& text) { options->view = parseView(text); },
         "error picture: eye and look-at point in ground-truth coordinates (default: an\n"
         "automatic view)")
      ->type_name("EX,EY,EZ,AX,AY,AZ");
  positive("--max-error", &options->max_error_m, "error picture: error of the top colour, metres");
  positive("--threads", &options->threads, "threads (at most 64)");
  app.footer(kFooter);
}

/// Checks between options and that the inputs exist; throws UsageError.
void checkOptions(Options* options) {
  options->threads = std::min(options->threads, 64);
  if (!options->gt_mesh.empty() && options->mesh.empty()) {
    throw UsageError("--gt-mesh needs --mesh (the reconstruction)");
  }
  if (!options->height_png.empty() && options->mesh.empty()) {
    throw UsageError("--height-png needs --mesh");
  }
  if (!options->mesh.empty() && options->gt_mesh.empty() && options->height_png.empty()) {
    throw UsageError("--mesh needs --gt-mesh (the ground truth) or --height-png");
  }
  if (options->gt_trajectory.empty() != options->trajectory.empty()) {
    throw UsageError(options->trajectory.empty() ? "--gt-trajectory needs --trajectory"
                                                 : "--trajectory needs --gt-trajectory");
  }
  if (options->mesh.empty() && options->trajectory.empty()) {
    throw UsageError(
        "nothing to evaluate: give --gt-mesh and --mesh, and/or --gt-trajectory and "
        "--trajectory (see --help)");
  }
  if (!options->error_png.empty() && options->gt_mesh.empty()) {
    throw UsageError("--error-png needs --gt-mesh and --mesh");
  }
  if (!options->trajectory_png.empty() && options->trajectory.empty()) {
    throw UsageError("--trajectory-png needs --gt-trajectory and --trajectory");
  }
  if (options->view && options->error_png.empty() && options->height_png.empty()) {
    throw UsageError("--view needs --error-png or --height-png");
  }
  LayerConfig grid;
  grid.voxel_size = static_cast<float>(options->voxel_size_m);
  grid.voxels_per_side = options->block_voxels;
  if (const std::string message = grid.validate(); !message.empty()) {
    throw UsageError("--voxel-size / --block-voxels: " + message);
  }
  // Inputs must exist before any work starts.
  for (const std::string* path :
       {&options->gt_mesh, &options->mesh, &options->gt_trajectory, &options->trajectory}) {
    if (path->empty()) continue;
    std::error_code ec;
    if (!std::filesystem::is_regular_file(*path, ec)) {
      throw UsageError(*path + ": no such file");
    }
  }
}

std::string lowerExtension(const std::string& path) {
  std::string extension = std::filesystem::path(path).extension().string();
  std::transform(extension.begin(), extension.end(), extension.begin(),
                 [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  return extension;
}

Mesh loadMesh(const std::string& path, const char* what) {
  Mesh mesh;
  std::string error;
  const std::string extension = lowerExtension(path);
  bool ok = false;
  if (extension == ".ply") {
    ok = readPly(path, &mesh, &error);
  } else if (extension == ".obj") {
    ok = readObj(path, &mesh, &error);
  } else {
    throw UsageError(path + ": unsupported " + what + " format '" + extension +
                     "' (expected .ply or .obj)");
  }
  if (!ok) throw UsageError(std::string(what) + ": " + error);
  return mesh;
}

StampedTrajectory loadTrajectory(const std::string& path) {
  std::string error;
  std::optional<StampedTrajectory> trajectory = readTumTrajectory(path, &error);
  if (!trajectory) throw UsageError(error);
  return std::move(*trajectory);
}

std::string millimetres(double metres) {
  char buffer[32];
  std::snprintf(buffer, sizeof(buffer), "%.2f mm", metres * 1e3);
  return buffer;
}

std::string percent(double share) {
  char buffer[32];
  std::snprintf(buffer, sizeof(buffer), "%.1f %%", share * 100.0);
  return buffer;
}

void writeTextFile(const std::string& path, const std::string& text) {
  std::ofstream out(path, std::ios::trunc);
  if (!out) throw EvaluationError(path + ": cannot open for writing");
  out << text;
  out.close();
  if (!out) throw EvaluationError(path + ": write failed");
}

// The reconstruction coloured by height (--height-png): turned so that --up is +z, heights
// above the lowest vertex, the colours spread up to the 99th percentile (a few stray
// vertices high above do not wash the picture out). Returns "" or what went wrong.
std::string writeHeightPng(const Options& options, const Mesh& reconstruction) {
  if (reconstruction.triangles.empty()) {
    return options.height_png + ": cannot render " + options.mesh +
           ": the reconstruction has no triangles (a point cloud)";
  }
  const Mesh turned = turnedUp(reconstruction, options.up);
  const std::vector<double> heights = vertexHeights(turned, Eigen::Vector3d::UnitZ());
  std::vector<double> sorted = heights;
  const auto p99 = sorted.begin() + static_cast<std::ptrdiff_t>(sorted.size() * 99 / 100);
  std::nth_element(sorted.begin(), p99, sorted.end());
  MeshErrorRenderConfig render;
  render.max_error_m = std::max(*p99, 0.1);
  render.millimetres = false;
  render.viewpoint = options.view;
  render.num_threads = options.threads;
  render.title = "height above the lowest surface, m (" +
                 std::filesystem::path(options.mesh).filename().string() + ")";
  std::string error;
  if (!writeMeshErrorPng(options.height_png, turned, heights, render, &error)) return error;
  std::printf("wrote %s\n", options.height_png.c_str());
  return {};
}

int run(const Options& options) {
  std::optional<TrajectoryEvaluation> trajectory_result;
  StampedTrajectory ground_truth_trajectory;
  StampedTrajectory estimated_trajectory;
  std::optional<MeshAccuracy> mesh_result;
  std::optional<SurfaceBlockCount> blocks;
  Mesh reconstruction;

  // Load every input first, so that a bad file fails before any long computation.
  if (!options.trajectory.empty()) {
    ground_truth_trajectory = loadTrajectory(options.gt_trajectory);
    estimated_trajectory = loadTrajectory(options.trajectory);
  }
  Mesh ground_truth_mesh;
  if (!options.mesh.empty()) reconstruction = loadMesh(options.mesh, "reconstruction");
  if (!options.gt_mesh.empty()) {
    ground_truth_mesh = loadMesh(options.gt_mesh, "ground-truth mesh");
    if (ground_truth_mesh.triangles.empty()) {
      throw UsageError(options.gt_mesh + ": the ground-truth mesh has no triangles");
    }
  }

  std::printf("cblox-eval\n");
  if (!options.trajectory.empty()) {
    TrajectoryEvaluationConfig evaluation_options;
    evaluation_options.association.max_difference_s = options.max_time_difference_s;
    evaluation_options.alignment = options.alignment;
    evaluation_options.rpe.delta = options.rpe_delta_frames;
    std::string error;
    trajectory_result = evaluateTrajectory(ground_truth_trajectory, estimated_trajectory,
                                           evaluation_options, &error);
    if (!trajectory_result) {
      throw EvaluationError(error + " (" + options.trajectory + " vs " + options.gt_trajectory +
                            ")");
    }
    const TrajectoryEvaluation& t = *trajectory_result;
    std::printf("trajectory: %s (%zu poses) vs %s (%zu poses), %zu matched\n",
                options.trajectory.c_str(), t.estimate_poses, options.gt_trajectory.c_str(),
                t.ground_truth_poses, t.matched_poses);
    std::printf("  ATE (%s): RMSE %.4f m, mean %.4f m, median %.4f m, max %.4f m",
                alignmentTypeName(t.ate.alignment_type), t.ate.translation_m.rmse,
                t.ate.translation_m.mean, t.ate.translation_m.median, t.ate.translation_m.max);
    if (t.ate.alignment_type == AlignmentType::kSim3) {
      std::printf(", scale %.4f", t.ate.alignment.scale);
    }
    std::printf(
        "\n  RPE (%d frame%s, %zu pairs): translation RMSE %.4f m, rotation RMSE %.3f deg\n",
        options.rpe_delta_frames, options.rpe_delta_frames == 1 ? "" : "s",
        t.rpe.translation_m.count, t.rpe.translation_m.rmse, t.rpe.rotation_deg.rmse);
  }

  if (!options.gt_mesh.empty()) {
    std::string error;
    const std::unique_ptr<TriangleMeshRaycaster> truth =
        TriangleMeshRaycaster::create(ground_truth_mesh, &error);
    if (!truth) throw UsageError(options.gt_mesh + ": " + error);
    MeshAccuracyConfig accuracy_options;
    accuracy_options.completeness_threshold_m = options.threshold_m;
    accuracy_options.surface_sample_spacing_m = options.sample_spacing_m;
    accuracy_options.max_distance_m = options.max_distance_m;
    accuracy_options.num_threads = options.threads;
    if (trajectory_result && options.mesh_align && options.alignment != AlignmentType::kNone) {
      accuracy_options.T_G_R = trajectory_result->ate.alignment;
    }
    mesh_result = evaluateMeshAccuracy(*truth, reconstruction, accuracy_options, &error);
    if (!mesh_result) throw EvaluationError(error + " (" + options.mesh + ")");
    const MeshAccuracy& m = *mesh_result;
    std::printf("mesh: %s (%zu vertices, %zu triangles) vs %s (%zu triangles, %.3f m^2)\n",
                options.mesh.c_str(), m.reconstruction_vertices, m.reconstruction_triangles,
                options.gt_mesh.c_str(), m.ground_truth_triangles, m.ground_truth_area_m2);
    if (m.T_G_R) {
      std::printf("  reconstruction aligned with the trajectory's %s alignment first\n",
                  alignmentTypeName(options.alignment));
    }
    std::printf("  accuracy: RMSE %s, mean %s, median %s, p90 %s, max %s (%zu vertices",
                millimetres(m.accuracy_m.rmse).c_str(), millimetres(m.accuracy_m.mean).c_str(),
                millimetres(m.accuracy_m.median).c_str(), millimetres(m.accuracy_m.p90).c_str(),
                millimetres(m.accuracy_m.max).c_str(), m.accuracy_m.count);
    if (std::isfinite(m.max_distance_m)) {
      std::printf(", %zu outliers beyond %s", m.outlier_vertices,
                  millimetres(m.max_distance_m).c_str());
    }
    std::printf(
        ")\n  completeness: %s of %zu ground-truth samples within %s of the %s "
        "(precision %s, F-score %s)\n",
        percent(m.completeness).c_str(), m.ground_truth_samples,
        millimetres(m.completeness_threshold_m).c_str(),
        m.completeness_reference == "vertices" ? "vertices" : "reconstruction",
        percent(m.precision).c_str(), percent(m.f_score).c_str());

    LayerConfig grid;
    grid.voxel_size = static_cast<float>(options.voxel_size_m);
    grid.voxels_per_side = options.block_voxels;
    blocks = countSurfaceBlocks(reconstruction, grid, &error);
    if (!blocks) throw EvaluationError(error + " (" + options.mesh + ")");
    std::printf(
        "  map: %zu blocks of %d^3 x %s voxels hold the surface (%.2f MiB of voxels; a "
        "lower bound of the TSDF map)\n",
        blocks->blocks, blocks->voxels_per_side, millimetres(blocks->voxel_size_m).c_str(),
        blocks->voxel_bytes / 1048576.0);
  }
  if (options.map_blocks || options.map_bytes) {
    std::printf("  map as reported: %s blocks, %s bytes\n",
                options.map_blocks ? std::to_string(*options.map_blocks).c_str() : "?",
                options.map_bytes ? std::to_string(*options.map_bytes).c_str() : "?");
  }

  // Outputs. Every one is attempted; the first failure decides the exit status.
  std::string failure;
  if (!options.json.empty()) {
    using Json = nlohmann::ordered_json;
    const auto path_or_null = [](const std::string& path) {
      return path.empty() ? Json(nullptr) : Json(path);
    };
    const auto count_or_null = [](const std::optional<size_t>& count) {
      return count ? Json(*count) : Json(nullptr);
    };
    Json root;
    root["inputs"] = {{"gt_mesh", path_or_null(options.gt_mesh)},
                      {"mesh", path_or_null(options.mesh)},
                      {"gt_trajectory", path_or_null(options.gt_trajectory)},
                      {"trajectory", path_or_null(options.trajectory)},
                      {"align", alignmentTypeName(options.alignment)},
                      {"mesh_aligned", mesh_result && mesh_result->T_G_R.has_value()}};
    root["mesh"] = mesh_result ? mesh_result->toJson() : Json(nullptr);
    Json surface_blocks(nullptr);
    if (blocks) {
      surface_blocks = {{"voxel_size_m", blocks->voxel_size_m},
                        {"voxels_per_side", static_cast<size_t>(blocks->voxels_per_side)},
                        {"blocks", blocks->blocks},
                        {"voxel_bytes", blocks->voxel_bytes}};
    }
    root["map"] = {{"surface_blocks", surface_blocks},
                   {"reported_blocks", count_or_null(options.map_blocks)},
                   {"reported_bytes", count_or_null(options.map_bytes)}};
    root["trajectory"] = trajectory_result ? trajectory_result->toJson() : Json(nullptr);
    try {
      // Paths are copied as they are; bytes that are not UTF-8 become U+FFFD.
      writeTextFile(options.json, root.dump(2, ' ', false, Json::error_handler_t::replace) + "\n");
      std::printf("wrote %s\n", options.json.c_str());
    } catch (const EvaluationError& e) {
      std::fprintf(stderr, "cblox-eval: %s\n", e.what());
      if (failure.empty()) failure = e.what();
    }
  }
  if (!options.error_png.empty() && mesh_result) {
    MeshErrorRenderConfig render;
    render.max_error_m = options.max_error_m;
    render.viewpoint = options.view;
    render.num_threads = options.threads;
    render.title = "vertex error: RMSE " + millimetres(mesh_result->accuracy_m.rmse) + ", median " +
                   millimetres(mesh_result->accuracy_m.median) + " (" +
                   std::filesystem::path(options.mesh).filename().string() + ")";
    const Mesh aligned =
        mesh_result->T_G_R ? alignMesh(reconstruction, *mesh_result->T_G_R) : reconstruction;
    std::string error;
    if (aligned.triangles.empty()) {
      error = options.error_png + ": cannot render " + options.mesh +
              ": the reconstruction has no triangles (a point cloud)";
    } else if (writeMeshErrorPng(options.error_png, aligned, mesh_result->vertex_errors_m, render,
                                 &error)) {
      std::printf("wrote %s\n", options.error_png.c_str());
      error.clear();
    }
    if (!error.empty()) {
      std::fprintf(stderr, "cblox-eval: %s\n", error.c_str());
      if (failure.empty()) failure = error;
    }
  }
  if (!options.height_png.empty()) {
    if (const std::string error = writeHeightPng(options, reconstruction); !error.empty()) {
      std::fprintf(stderr, "cblox-eval: %s\n", error.c_str());
      if (failure.empty()) failure = error;
    }
  }
  if (!options.trajectory_png.empty() && trajectory_result) {
    TrajectoryPlotConfig plot;
    char title[128];
    std::snprintf(title, sizeof(title), "ATE RMSE %.4f m (%s alignment, %zu poses)",
                  trajectory_result->ate.translation_m.rmse,
                  alignmentTypeName(trajectory_result->ate.alignment_type),
                  trajectory_result->matched_poses);
    plot.title = title;
    plot.estimate_label = "estimate (aligned)";
    std::string error;
    if (writeTrajectoryPlotPng(
            options.trajectory_png, ground_truth_trajectory,
            applyAlignment(estimated_trajectory, trajectory_result->ate.alignment), plot, &error)) {
      std::printf("wrote %s\n", options.trajectory_png.c_str());
    } else {
      std::fprintf(stderr, "cblox-eval: %s\n", error.c_str());
      if (failure.empty()) failure = error;
    }
  }
  return failure.empty() ? 0 : kExitFailure;
}

}  // namespace
}  // namespace cblox

int main(int argc, char** argv) {
  cblox::Options options;
  CLI::App app{
      "cblox-eval: accuracy of a reconstruction against ground truth (mesh and/or trajectory);\n"
      "prints a summary and writes JSON and pictures.",
      "cblox-eval"};
  cblox::addOptions(app, &options);
  if (const std::optional<int> code = cblox::parseCommandLine(app, argc, argv)) return *code;
  try {
    cblox::checkOptions(&options);
    return cblox::run(options);
  } catch (const cblox::UsageError& e) {
    std::cerr << "cblox-eval: " << e.what() << "\n";
    return cblox::kExitUsage;
  } catch (const std::exception& e) {
    std::cerr << "cblox-eval: " << e.what() << "\n";
    return cblox::kExitFailure;
  }
}
