// Map maintenance evaluation (issue 6 item 5, the paper's Table II) on the simulator: one run
// of the sparse SLAM over a scene with place revisiting feeds, frame by frame, several dense
// mappers that differ only in how they use the poses:
//   (a) gt     one volume, ground-truth poses (the reference),
//   (b) naive  one volume, the tracker's live frame poses, never corrected,
//   (c) off    subvolumes moved by every keyframe pose correction, no fusion,
//   (d) on     the same with map maintenance: covisible subvolumes whose conditional
//              covariance q = 1/||Sigma_{i|j}||_2 reaches q_min are fused (one mapper per
//              q_min of the sweep, each with its own covariance service on the live map),
//              q asked of the keyframes the default maintenance.pair_keyframes names
//              (most_shared_on_revisits: the two that share the most landmarks when their
//              ids are --revisit-keyframe-gap apart, else the anchors); for each q_min of
//              --anchors-q-min, q always asked of the two anchor keyframes (the paper's
//              rule, for comparison); for each of --most-shared-q-min, always of the
//              keyframes that share the most landmarks (most_shared, for comparison); for
//              each of --revisit-overlap-q-min, explicitly most_shared_on_revisits;
//              with --revisit-q-min, an off map and these q_min with subvolumes also
//              started at revisits (subvolumes.revisit_anchor_distance_m); with
//              --revisit-frames-q-min, an off map and these q_min with frames tracked in an
//              older subvolume anchored to it (subvolumes.revisit_after_frames, pairs sharing
//              an anchor fused exactly).
// At the end every map is meshed (the projection of its subvolumes into one volume) and
// compared with the scene's exact surface: vertex RMSE and median, and the map's size in
// TSDF blocks (over all subvolumes). Maps made with the tracker's poses are first aligned
// (SE(3), final keyframe positions to the true ones, as for ATE). --depth-noise K adds the
// sensor model's depth noise sigma = K z^2 (metres; the stereo images stay clean).
// --depth stereo: every map integrates depth computed from the stereo pair by the pipeline's
// own dense matcher (cblox-capture's stereo_depth: SGBM at half size, config/capture.yaml's
// defaults) instead of the renderer's exact depth, as the paper's maps came from stereo; the
// gt map then carries the sensor's error too, and "RMSE / gt" compares poses, not sensors.
//
//   cblox-bench-maintenance [--scene room|hall|town] [--trajectory loop|two-loops]
//                           [--laps 2] [--frames N]
//                           [--voxel 0.05] [--keyframes-per-subvolume 10]
//                           [--max-anchor-distance M] [--revisit-distance R]
//                           [--revisit-q-min Q,... [--revisit-variant-distance 1]]
//                           [--revisit-frames F] [--revisit-max-frames M]
//                           [--revisit-frames-q-min Q,... [--revisit-variant-frames 10]]
//                           [--depth exact|stereo] [--depth-noise K] [--no-sync-slam]
//                           [--min-shared-landmarks 30] [--min-shared-ratio 0.05]
//                           [--q-min 3e3,1e4,3e4,1e5] [--most-shared-q-min Q,...]
//                           [--anchors-q-min Q,...]
//                           [--revisit-overlap-q-min Q,... [--revisit-keyframe-gap 30]]
//                           [--planning-samples N] [--carving-depth D] [--band-blocks B]
//                           [--surface-margin M]
//                           [--out DIR]
//
// Mappers integrate every frame (no time budget, waited for) so the comparison does not
// depend on the machine's load; with --sync-slam (the default) the SLAM's local mapping and
// loop closing are waited for after every frame too (ORB-SLAM2 run offline), so the
// tracker's poses do not depend on it either, and the mappers run on the input clock
// (MaintenanceClock::kInput) with each frame's keyframes applied before the frame and its
// covariance requests answered and applied after it: a run is a function of its inputs, so
// two runs print the same figures (--no-sync-slam: as in real time). --out writes
// DIR/maintenance_<scene>.json and DIR/maintenance_<scene>_sweep.png (map size against RMSE
// for every variant; <scene>_two-loops for that route). For every fusion variant it also
// prints the answered pairs: q (median, share >= q_min) and the distance between the two
// keyframes asked about, so the reason for rejections is visible. --planning-samples N: every
// map keeps its planning map (the distance fields, MapperConfig::planning), scored at the end
// at N random points of the scene's bounds against the exact signed distance (Embree closest
// points; distance_field_accuracy.h): error, the unsafe count, observed free space answered
// unknown; maps made with the tracker's poses are queried through the trajectory alignment.
// --carving-depth D: the projective integrator also maps the free space in front of the
// surfaces up to depth D (IntegratorConfig::projective_carving_depth_m). --band-blocks B:
// the fields' band rings (planning.band_blocks; default auto: 1 with carving, else 0).
// --surface-margin M: free answers beside obstacles lowered by M voxels
// (planning.surface_margin_voxels; 0: the fields' own values).

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <map>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <thread>
#include <vector>

#include <unistd.h>

#include <CLI/CLI.hpp>
#include <nlohmann/json.hpp>

#include "core/common/quantile.h"
#include "core/eval/distance_field_accuracy.h"
#include "core/eval/mesh_accuracy.h"
#include "core/eval/scatter_plot.h"
#include "core/eval/umeyama.h"
#include "core/mapping/mapper.h"
#include "core/raycast/triangle_mesh_raycaster.h"
#include "core/submap/submap_fusion.h"
#include "core/tracking/keyframe_covariance_service.h"
#include "core/tracking/slam_system.h"
#include "daemon/common/cli.h"
#include "daemon/tracker/tracker_config.h"
#include "drivers/open_frame_source.h"
#include "drivers/sim/builtin_scenes.h"
#include "drivers/stereo_depth/stereo_depth.h"

namespace cblox {
namespace {

using Clock = std::chrono::steady_clock;

enum class Kind { kGroundTruth, kNaive, kOff, kOn };

// One answered pair of a fusion variant.
struct PairAnswer {
  bool ok = false;
  double q = 0.0;
  double distance_m = 0.0;  ///< between the two keyframes asked about, when they were made
  int keyframe_shared = 0;
};

struct Variant {
  std::string name;
  Kind kind = Kind::kOff;
  double q_min = 0.0;
  PairKeyframes pair_keyframes = FusionSchedulerConfig{}.pair_keyframes;
  double revisit_m = 0.0;  ///< subvolumes.revisit_anchor_distance_m
  int revisit_frames = 0;  ///< subvolumes.revisit_after_frames
  std::mutex pairs_mutex;
  std::map<int64_t, std::vector<FusionPair>> requested;  // by request id, until answered
  std::vector<PairAnswer> answers;
  std::unique_ptr<Mapper> mapper;
  std::unique_ptr<KeyframeCovarianceService> covariance;
  // Results.
  size_t subvolumes = 0, blocks = 0, vertices = 0;
  double rmse_m = 0.0, median_m = 0.0;
  FusionSchedulerStats fusion;
  std::optional<DistanceFieldAccuracy> planning;  // with --planning-samples
  PlanningMapStats planning_stats;                // when planning was scored
};

MapperConfig baseConfig(float voxel, const std::filesystem::path& out, bool deterministic) {
  MapperConfig config;
  if (deterministic) config.maintenance_clock = MaintenanceClock::kInput;
  config.layer = LayerConfig{voxel, 8};
  config.integrator.truncation_distance_m = 3.0f * voxel;
  config.integrator.max_integration_time_s = 0.0;  // every frame whole: load-independent
  config.output_dir = out.string();
  config.worker_sched_idle = false;  // fusion must not starve behind the bench's own work
  config.worker_niceness = 0;
  config.pending_capacity = 4;
  config.max_pose_wait_s = 5.0;
  return config;
}

/// Scores every variant's planning map at `samples` random points of the scene's bounds
/// against the exact signed distances (Embree closest points) and the depth images' free
/// space, and prints a table. Maps built with the tracker's poses are queried at the points
/// carried into their frame by the inverse of the trajectory alignment (T_true_estimated).
void scorePlanningMaps(const TriangleMeshRaycaster& truth, const std::vector<DepthView>& views,
                       size_t samples, float voxel,
                       const std::optional<Transformationd>& T_true_estimated,
                       std::vector<std::unique_ptr<Variant>>* variants) {
  const MapperConfig& config = variants->front()->mapper->config();
  DistanceTruthConfig truth_config;
  truth_config.samples = samples;
  truth_config.box =
      Eigen::AlignedBox3d(truth.bounds().min().cast<double>(), truth.bounds().max().cast<double>());
  truth_config.truncation_m = config.integrator.truncation_distance_m;
  truth_config.free_margin_m = voxel;
  truth_config.view_stride = 2;
  const Clock::time_point start = Clock::now();
  std::string error;
  const auto truth_samples = sampleDistanceTruth(truth, views, truth_config, &error);
  if (!truth_samples) {
    std::fprintf(stderr, "planning truth: %s\n", error.c_str());
    return;
  }
  std::fprintf(stderr, "planning truth: %zu points, %zu views (every 2nd used), %.1f s\n", samples,
               views.size(), std::chrono::duration<double>(Clock::now() - start).count());
  const double max_distance = config.planning.esdf.max_distance_m;
  for (auto& v : *variants) {
    if (!v->mapper->syncPlanningMap(std::chrono::minutes(5)) || !v->mapper->planningMap()) {
      std::fprintf(stderr, "%s: the planning map did not follow the map\n", v->name.c_str());
      continue;
    }
    const bool tracked = v->kind != Kind::kGroundTruth;
    std::vector<Eigen::Vector3d> points;
    points.reserve(truth_samples->size());
    for (const DistanceTruthSample& s : *truth_samples) {
      points.push_back(tracked && T_true_estimated ? T_true_estimated->inverse() * s.p_G : s.p_G);
    }
    std::vector<DistanceAnswer> answers;
    v->mapper->planningMap()->queryBatch(points, &answers);
    v->planning_stats = v->mapper->planningMap()->stats();
    std::vector<FieldAnswer> field(answers.size());
    for (size_t i = 0; i < answers.size(); ++i) {
      field[i] = FieldAnswer{answers[i].state, answers[i].distance};
    }
    v->planning = scoreDistanceField(*truth_samples, field, voxel, max_distance);
  }
  std::printf(
      "\nplanning maps at %zu random points of the scene's bounds (max_distance_m %.1f, voxel "
      "%.3f m), against the exact signed distance; unsafe = inside or within one voxel of a "
      "surface, answered free farther than one voxel; observed free = a depth image saw "
      "through the point more than truncation + one voxel before the surface; nearest surface "
      "seen = a depth image saw the surface point closest to the point:\n"
      "| map | field blocks (band) | field MiB | free / occupied / unknown answers | compared | "
      "error median (voxels) | p99 | max | nearest surface seen: compared | error median | p99 | "
      "max | unsafe (of near) | of them over by > 1 voxel | unsafe, nearest surface seen (over by "
      "> 1 voxel) | observed free answered unknown | far answered occupied |\n"
      "|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|\n",
      samples, max_distance, voxel);
  for (const auto& v : *variants) {
    if (!v->planning) continue;
    const DistanceFieldAccuracy& a = *v->planning;
    std::printf(
        "| %s | %zu (%zu) | %.1f | %zu / %zu / %zu | %zu | %.3f | %.3f | %.2f | %zu | %.3f | "
        "%.3f | %.2f | %zu (of %zu) | %zu | %zu (%zu) | %zu of %zu (%.1f %%) | %zu |\n",
        v->name.c_str(), v->planning_stats.blocks, v->planning_stats.band_blocks,
        static_cast<double>(v->planning_stats.memory_bytes) / (1024.0 * 1024.0), a.answered_free,
        a.answered_occupied, a.answered_unknown, a.compared, a.error_median_voxels,
        a.error_p99_voxels, a.error_max_voxels, a.compared_seen, a.seen_error_median_voxels,
        a.seen_error_p99_voxels, a.seen_error_max_voxels, a.unsafe, a.near_obstacle,
        a.unsafe_by_a_voxel, a.unsafe_seen, a.unsafe_seen_by_a_voxel, a.observed_free_unknown,
        a.observed_free,
        a.observed_free > 0 ? 100.0 * static_cast<double>(a.observed_free_unknown) /
                                  static_cast<double>(a.observed_free)
                            : 0.0,
        a.far_answered_occupied);
  }
  std::fflush(stdout);
}

int run(int argc, char** argv) {
  std::string scene = "room", out_dir, vocabulary_path, config_path;
  int laps = 2;
  std::string trajectory = "loop";
  size_t max_frames = 0;
  float voxel = 0.05f;
  int keyframes_per_subvolume = MapperConfig{}.creation.max_keyframes_per_subvolume;
  double max_anchor_distance = MapperConfig{}.creation.max_anchor_distance_m;
  double revisit_distance = MapperConfig{}.creation.revisit_anchor_distance_m;
  std::vector<double> revisit_sweep;
  double revisit_variant_distance = 1.0;
  int revisit_frames = MapperConfig{}.creation.revisit_after_frames;
  std::vector<double> revisit_frames_sweep;
  int revisit_variant_frames = 10;
  int revisit_max_frames = MapperConfig{}.creation.revisit_max_frames;
  bool sync_slam = true;
  double depth_noise = 0.0;
  std::string depth_kind = "exact";
  CovisibilityGraphConfig candidates;
  std::vector<double> sweep = {3e3, 1e4, 3e4, 1e5};
  std::vector<double> most_shared_sweep;
  std::vector<double> revisit_overlap_sweep;
  std::vector<double> anchors_sweep;
  int revisit_keyframe_gap = FusionSchedulerConfig{}.revisit_keyframe_gap;
  size_t planning_samples = 0;
  int band_blocks = PlanningConfig{}.esdf.band_blocks;
  float surface_margin = PlanningConfig{}.esdf.surface_margin_voxels;
  float carving_depth = IntegratorConfig{}.projective_carving_depth_m;
#ifdef CBLOX_DEFAULT_VOCABULARY
  vocabulary_path = CBLOX_DEFAULT_VOCABULARY;
#endif
  CLI::App app{
      "cblox-bench-maintenance: map maintenance on a simulated scene (the paper's Table II):\n"
      "dense maps with ground-truth poses, live poses, subvolumes without and with fusion (a\n"
      "q_min sweep), each mesh against the exact scene.",
      "cblox-bench-maintenance"};
  app.add_option("--scene", scene, "room | hall | town")->capture_default_str();
  app.add_option("--trajectory", trajectory,
                 "the scene's route: loop, or two-loops (the town's second route)")
      ->capture_default_str();
  app.add_option("--laps", laps, "laps of the trajectory")->capture_default_str();
  app.add_option("--frames", max_frames, "frames at the most (0: all)")->capture_default_str();
  app.add_option("--voxel", voxel, "voxel size, metres")->capture_default_str();
  app.add_option("--keyframes-per-subvolume", keyframes_per_subvolume,
                 "a new subvolume after this many keyframes")
      ->capture_default_str();
  app.add_option("--max-anchor-distance", max_anchor_distance,
                 "a new subvolume after a keyframe this far from the anchor, metres (0: off)")
      ->capture_default_str();
  app.add_option("--revisit-distance", revisit_distance,
                 "a new subvolume at a keyframe this near an older anchor, metres (0: off)")
      ->capture_default_str();
  app.add_option("--revisit-q-min", revisit_sweep,
                 "also an off map and these q_min with subvolumes anchored at revisits "
                 "(--revisit-variant-distance; comma-separated; default none)")
      ->delimiter(',')
      ->allow_extra_args(false)
      ->expected(0, 1 << 20)
      ->type_name("Q[,Q...]");
  app.add_option("--revisit-variant-distance", revisit_variant_distance,
                 "the revisit distance of the --revisit-q-min variants, metres (> 0)")
      ->capture_default_str();
  app.add_option("--revisit-frames", revisit_frames,
                 "frames tracked in an older subvolume this many times in a row start a "
                 "subvolume sharing its anchor (0: off)")
      ->capture_default_str();
  app.add_option("--revisit-max-frames", revisit_max_frames,
                 "a revisit subvolume takes at most this many frames (0: no bound)")
      ->capture_default_str();
  app.add_option("--revisit-frames-q-min", revisit_frames_sweep,
                 "also an off map and these q_min with --revisit-variant-frames (comma-separated; "
                 "default none)")
      ->delimiter(',')
      ->allow_extra_args(false)
      ->expected(0, 1 << 20)
      ->type_name("Q[,Q...]");
  app.add_option("--revisit-variant-frames", revisit_variant_frames,
                 "the revisit_after_frames of the --revisit-frames-q-min variants (>= 1)")
      ->capture_default_str();
  app.add_flag("--sync-slam,!--no-sync-slam", sync_slam,
               "wait for local mapping and loop closing after every frame (default: yes)");
  app.add_option("--min-shared-ratio", candidates.min_shared_ratio,
                 "fusion candidates: share of landmarks seen by both")
      ->capture_default_str();
  app.add_option("--min-shared-landmarks", candidates.min_shared_landmarks,
                 "fusion candidates: landmarks seen by both")
      ->capture_default_str();
  app.add_option("--depth", depth_kind,
                 "exact: the renderer's depth; stereo: depth from the stereo pair by "
                 "cblox-capture's dense matcher (SGBM, half size)")
      ->check(CLI::IsMember({"exact", "stereo"}))
      ->capture_default_str();
  app.add_option("--depth-noise", depth_noise, "depth noise sigma = K z^2 (metres)")
      ->type_name("K")
      ->capture_default_str();
  app.add_option("--q-min", sweep, "the q_min sweep, comma-separated")
      ->delimiter(',')
      ->allow_extra_args(false)
      ->type_name("Q[,Q...]");
  app.add_option("--most-shared-q-min", most_shared_sweep,
                 "also these q_min with q asked of the keyframes that share the most "
                 "landmarks (comma-separated; default none)")
      ->delimiter(',')
      ->allow_extra_args(false)
      ->expected(0, 1 << 20)
      ->type_name("Q[,Q...]");
  app.add_option("--revisit-overlap-q-min", revisit_overlap_sweep,
                 "also these q_min with q asked of the most shared keyframes when they are "
                 "--revisit-keyframe-gap ids apart, else of the anchors (comma-separated; "
                 "default none)")
      ->delimiter(',')
      ->allow_extra_args(false)
      ->expected(0, 1 << 20)
      ->type_name("Q[,Q...]");
  app.add_option("--anchors-q-min", anchors_sweep,
                 "also these q_min with q always asked of the subvolumes' anchors "
                 "(maintenance.pair_keyframes: anchors, the paper's rule; comma-separated; "
                 "default none)")
      ->delimiter(',')
      ->allow_extra_args(false)
      ->expected(0, 1 << 20)
      ->type_name("Q[,Q...]");
  app.add_option("--revisit-keyframe-gap", revisit_keyframe_gap,
                 "keyframe ids between the most shared keyframes of a revisit pair")
      ->capture_default_str();
  app.add_option("--planning-samples", planning_samples,
                 "every map keeps its planning map (distance fields), scored at the end at this "
                 "many random points of the scene against the exact distances (0: off)")
      ->capture_default_str();
  app.add_option("--carving-depth", carving_depth,
                 "the projective integrator maps free space up to this depth, metres "
                 "(integrator.projective_carving_depth_m; 0: the surfaces' band only)")
      ->capture_default_str();
  app.add_option("--band-blocks", band_blocks,
                 "rings of band blocks around each field's TSDF blocks (planning.band_blocks; "
                 "-1: auto, 1 with --carving-depth, else 0)")
      ->check(CLI::Range(-1, 2))
      ->capture_default_str();
  app.add_option("--surface-margin", surface_margin,
                 "free answers beside obstacles are lowered by this many voxels "
                 "(planning.surface_margin_voxels)")
      ->check(CLI::Range(0.0, 1.0))
      ->capture_default_str();
  app.add_option("--out", out_dir, "writes DIR/maintenance_<scene>.json and the sweep picture")
      ->type_name("DIR");
  app.add_option("--vocabulary", vocabulary_path, "vocabulary file")->capture_default_str();
  app.add_option("--config", config_path,
                 "a tracker.yaml: its SLAM settings replace the defaults (camera settings unused)")
      ->type_name("FILE");
  if (const std::optional<int> code = parseCommandLine(app, argc, argv)) return *code;
  if (sweep.empty() || !(voxel > 0.0f) || !(revisit_variant_distance > 0.0) ||
      revisit_variant_frames < 1 || revisit_frames < 0 || revisit_max_frames < 0 ||
      revisit_keyframe_gap < 1) {
    std::fprintf(stderr,
                 "--q-min needs at least one value, --voxel and --revisit-variant-distance "
                 "must be > 0, --revisit-variant-frames >= 1, --revisit-frames and "
                 "--revisit-max-frames >= 0, --revisit-keyframe-gap >= 1\n");
    return 2;
  }
  if (depth_kind == "stereo" && depth_noise != 0.0) {
    std::fprintf(stderr,
                 "--depth-noise adds noise to the renderer's depth, which --depth stereo does "
                 "not use\n");
    return 2;
  }
  std::string error;
  const auto vocabulary = BinaryVocabulary::load(vocabulary_path, &error);
  if (!vocabulary) {
    std::fprintf(stderr, "vocabulary: %s\n", error.c_str());
    return 2;
  }
  SourceConfig options;
  options.trajectory = trajectory;
  options.laps = laps;
  options.max_frames = max_frames;
  options.sim.noise.depth_noise_per_m2 = depth_noise;  // the stereo pair stays clean
  auto source = openFrameSource("sim:" + scene, options, &error);
  if (!source) {
    std::fprintf(stderr, "%s\n", error.c_str());
    return 2;
  }
  const SourceInfo info = source->info();
  if (!info.stereo || !info.depth_intrinsics) {
    std::fprintf(stderr, "the source must deliver stereo and depth\n");
    return 2;
  }
  const RectifiedStereoCalibration& calibration = *info.stereo;
  std::unique_ptr<StereoDepthEstimator> stereo_depth;
  if (depth_kind == "stereo") {
    StereoDepthConfig stereo_config;  // cblox-capture's defaults
    stereo_config.max_depth_m = info.depth_max_m;
    stereo_depth = StereoDepthEstimator::create(calibration, stereo_config, &error);
    if (!stereo_depth) {
      std::fprintf(stderr, "stereo depth: %s\n", error.c_str());
      return 2;
    }
  }
  const TrackingCamera camera = makeTrackingCamera(calibration.intrinsics, calibration.baseline_m);
  const std::optional<SlamSystemConfig> slam_config = loadSlamSettings(config_path, &error);
  if (!slam_config) {
    std::fprintf(stderr, "%s\n", error.c_str());
    return 2;
  }
  SlamSystem slam(camera, *slam_config, &*vocabulary);

  const std::filesystem::path work =
      std::filesystem::temp_directory_path() /
      ("cblox_bench_maintenance_" + scene + "_" + trajectory + "_" + std::to_string(getpid()));
  std::filesystem::create_directories(work);
  std::vector<std::unique_ptr<Variant>> variants;
  // Covariance answers: errors by message (first 60 characters) and times per request.
  std::mutex errors_mutex;
  std::map<std::string, int> errors;
  std::vector<double> build_ms;
  size_t reused = 0;  // replies from a kept linearization
  // Keyframe positions when they were made (for the distance of the pairs asked about).
  std::mutex positions_mutex;
  std::map<int64_t, Eigen::Vector3d> keyframe_positions;
  const PairKeyframes default_pairs = FusionSchedulerConfig{}.pair_keyframes;
  auto add = [&](std::string name, Kind kind, double q_min,
                 PairKeyframes pair_keyframes = FusionSchedulerConfig{}.pair_keyframes,
                 std::optional<double> revisit_m = std::nullopt,
                 std::optional<int> frames = std::nullopt) {
    auto v = std::make_unique<Variant>();
    v->name = std::move(name);
    v->kind = kind;
    v->q_min = q_min;
    v->pair_keyframes = pair_keyframes;
    v->revisit_m = revisit_m.value_or(revisit_distance);
    v->revisit_frames = frames.value_or(revisit_frames);
    MapperConfig config = baseConfig(voxel, work, sync_slam);
    config.planning.enabled = planning_samples > 0;
    config.integrator.projective_carving_depth_m = carving_depth;
    config.planning.esdf.band_blocks = band_blocks;
    config.planning.esdf.surface_margin_voxels = surface_margin;
    if (kind == Kind::kGroundTruth || kind == Kind::kNaive) {
      config.pose_source = PoseSource::kGroundTruth;          // poses fed as given, never corrected
      config.creation.max_keyframes_per_subvolume = 1 << 30;  // one volume
    } else {
      config.pose_source = PoseSource::kTracker;
      config.creation.max_keyframes_per_subvolume = keyframes_per_subvolume;
      config.creation.max_anchor_distance_m = max_anchor_distance;
      config.creation.revisit_anchor_distance_m = v->revisit_m;
      config.creation.revisit_after_frames = v->revisit_frames;
      config.creation.revisit_max_frames = revisit_max_frames;
      config.maintenance.enabled = kind == Kind::kOn;
      config.maintenance.candidates = candidates;
      if (kind == Kind::kOn) config.maintenance.q_min = q_min;
      config.maintenance.pair_keyframes = pair_keyframes;
      config.maintenance.revisit_keyframe_gap = revisit_keyframe_gap;
    }
    v->mapper = std::make_unique<Mapper>(config, [](const std::string&) {});
    if (kind == Kind::kOn) {
      Mapper* mapper = v->mapper.get();
      Variant* variant = v.get();
      // Waited for per frame, the drive runs slower or faster than its clock: as in
      // cblox-replay, linearizations are not spaced by wall-clock time then. In real time the
      // live tracker's spacing applies.
      KeyframeCovarianceServiceConfig covariance_config;
      if (sync_slam) covariance_config.min_linearization_interval_s = 0.0;
      v->covariance = std::make_unique<KeyframeCovarianceService>(
          slam.map(), camera, slam.pyramid(), covariance_config,
          [mapper, variant, &errors_mutex, &errors, &build_ms, &reused, &positions_mutex,
           &keyframe_positions](const KeyframeCovarianceReply& reply) {
            {
              std::lock_guard<std::mutex> lock(variant->pairs_mutex);
              const auto it = variant->requested.find(reply.request_id);
              if (it != variant->requested.end() && it->second.size() == reply.results.size()) {
                std::lock_guard<std::mutex> positions_lock(positions_mutex);
                for (size_t k = 0; k < reply.results.size(); ++k) {
                  const FusionPair& p = it->second[k];
                  PairAnswer a{reply.results[k].ok, reply.results[k].q, 0.0,
                               p.keyframe_shared_landmarks};
                  const auto i = keyframe_positions.find(p.newer_keyframe);
                  const auto j = keyframe_positions.find(p.older_keyframe);
                  if (i != keyframe_positions.end() && j != keyframe_positions.end()) {
                    a.distance_m = (i->second - j->second).norm();
                  }
                  variant->answers.push_back(a);
                }
              }
              if (it != variant->requested.end()) variant->requested.erase(it);
            }
            std::vector<FusionCovarianceAnswer> answers;
            {
              std::lock_guard<std::mutex> lock(errors_mutex);
              build_ms.push_back(reply.build_ms + reply.solve_ms);
              if (reply.reused) ++reused;
              for (const ConditionalCovariance& r : reply.results) {
                if (!r.ok) ++errors[r.error.substr(0, 60)];
              }
            }
            for (const ConditionalCovariance& r : reply.results) {
              answers.push_back(FusionCovarianceAnswer{r.ok, r.error, r.q});
            }
            mapper->onCovarianceReply(reply.request_id, std::move(answers));
          });
      KeyframeCovarianceService* service = v->covariance.get();
      mapper->setCovarianceRequester([service, variant](const FusionCovarianceRequest& request) {
        {
          std::lock_guard<std::mutex> lock(variant->pairs_mutex);
          variant->requested[request.request_id] = request.pairs;
        }
        KeyframeCovarianceRequest r;
        r.request_id = request.request_id;
        for (const FusionPair& p : request.pairs) {
          r.pairs.push_back(KeyframePair{static_cast<uint64_t>(p.newer_keyframe),
                                         static_cast<uint64_t>(p.older_keyframe)});
        }
        service->submit(std::move(r));
      });
      v->covariance->start();
    }
    std::string start_error;
    if (!v->mapper->start(&start_error)) {
      std::fprintf(stderr, "mapper %s: %s\n", v->name.c_str(), start_error.c_str());
      std::exit(1);
    }
    variants.push_back(std::move(v));
  };
  add("gt", Kind::kGroundTruth, 0.0);
  add("naive", Kind::kNaive, 0.0);
  add("off", Kind::kOff, 0.0);
  for (const double q : sweep) {
    char name[32];
    std::snprintf(name, sizeof(name), "on q>=%.0g", q);
    add(name, Kind::kOn, q);
  }
  for (const double q : most_shared_sweep) {
    char name[40];
    std::snprintf(name, sizeof(name), "on q>=%.0g most shared", q);
    add(name, Kind::kOn, q, PairKeyframes::kMostShared);
  }
  for (const double q : anchors_sweep) {
    char name[40];
    std::snprintf(name, sizeof(name), "on q>=%.0g anchors", q);
    add(name, Kind::kOn, q, PairKeyframes::kAnchors);
  }
  for (const double q : revisit_overlap_sweep) {
    char name[48];
    std::snprintf(name, sizeof(name), "on q>=%.0g revisit overlap", q);
    add(name, Kind::kOn, q, PairKeyframes::kMostSharedOnRevisits);
  }
  if (!revisit_sweep.empty()) {
    add("off revisit", Kind::kOff, 0.0, default_pairs, revisit_variant_distance);
  }
  for (const double q : revisit_sweep) {
    char name[40];
    std::snprintf(name, sizeof(name), "on q>=%.0g revisit", q);
    add(name, Kind::kOn, q, default_pairs, revisit_variant_distance);
  }
  if (!revisit_frames_sweep.empty()) {
    add("off frames", Kind::kOff, 0.0, default_pairs, std::nullopt, revisit_variant_frames);
  }
  for (const double q : revisit_frames_sweep) {
    char name[40];
    std::snprintf(name, sizeof(name), "on q>=%.0g frames", q);
    add(name, Kind::kOn, q, default_pairs, std::nullopt, revisit_variant_frames);
  }

  std::map<uint64_t, Transformationd> truth_by_frame;  // for the trajectory alignment
  std::vector<DepthView> views;                        // the depth images' true poses

  // SLAM outputs, from its threads, handed to the tracker-mode mappers by the main loop.
  std::mutex mutex;
  std::vector<KeyframeInfo> keyframes;
  std::vector<KeyframePoseBatch> batches;
  slam.setKeyframeCallback([&](const KeyframeInfo& k) {
    {
      std::lock_guard<std::mutex> lock(positions_mutex);
      keyframe_positions[static_cast<int64_t>(k.id)] = k.T_G_K.translation();
    }
    std::lock_guard<std::mutex> lock(mutex);
    keyframes.push_back(k);
  });
  slam.setPoseCallback([&](const KeyframePoseBatch& batch, PoseUpdateReason) {
    std::lock_guard<std::mutex> lock(mutex);
    batches.push_back(batch);
  });
  auto deliver = [&] {
    std::vector<KeyframeInfo> k;
    std::vector<KeyframePoseBatch> b;
    {
      std::lock_guard<std::mutex> lock(mutex);
      k.swap(keyframes);
      b.swap(batches);
    }
    for (auto& v : variants) {
      if (v->kind != Kind::kOff && v->kind != Kind::kOn) continue;
      for (const KeyframeInfo& info_k : k) {
        v->mapper->onKeyframe(
            static_cast<KeyframeId>(info_k.id), info_k.timestamp_ns / 1000, info_k.T_G_K,
            std::vector<uint64_t>(info_k.landmark_ids.begin(), info_k.landmark_ids.end()));
      }
      for (const KeyframePoseBatch& batch : b) {
        v->mapper->onKeyframePoses(
            std::vector<std::pair<KeyframeId, Transformationd>>(batch.begin(), batch.end()));
      }
    }
  };
  auto waitAll = [&] {
    for (auto& v : variants) v->mapper->waitUntilIdle(std::chrono::seconds(120));
  };
  // Until no covariance request is outstanding and every mapper is idle: a reply can start a
  // fusion and the next request. Stops when a round answers nothing (a request the service
  // dropped would otherwise be waited for forever).
  auto settle = [&] {
    size_t outstanding_before = SIZE_MAX;
    while (true) {
      waitAll();
      size_t outstanding = 0;
      for (auto& v : variants) {
        std::lock_guard<std::mutex> lock(v->pairs_mutex);
        outstanding += v->requested.size();
      }
      if (outstanding == 0 || outstanding == outstanding_before) return;
      outstanding_before = outstanding;
      for (auto& v : variants) {
        if (v->covariance) v->covariance->waitUntilIdle();
      }
    }
  };

  const size_t total = info.frame_count.value_or(0);
  const auto start = Clock::now();
  CaptureFrame frame;
  size_t n = 0, lost = 0;
  while (source->next(&frame, &error) == FrameSource::Status::kFrame) {
    truth_by_frame[static_cast<uint64_t>(frame.frame_id)] = *frame.T_G_C;
    const TrackingResult r =
        slam.trackStereo(static_cast<uint64_t>(frame.frame_id), frame.timestamp_ns, frame.left,
                         frame.right, frame.T_G_C->inverse());
    if (sync_slam) slam.waitUntilIdle();  // keyframes and corrections of this frame are out
    deliver();
    if (sync_slam) waitAll();  // ... and applied before the frame is integrated
    const int64_t utime = frame.timestamp_ns / 1000;
    DepthFrame depth;
    depth.utime = utime;
    depth.frame_id = frame.frame_id;
    if (stereo_depth) {  // the left camera's depth at half size, no colour (as capture's)
      stereo_depth->compute(frame.left, frame.right, &depth.depth);
      depth.intrinsics = stereo_depth->depthIntrinsics();
      depth.T_B_D = Transformationd();
    } else {
      depth.depth = frame.depth;
      depth.color = frame.color;
      depth.intrinsics = *info.depth_intrinsics;
      depth.T_B_D = info.T_C_D;
    }
    depth.min_depth_m = static_cast<float>(info.depth_min_m);
    depth.max_depth_m = static_cast<float>(info.depth_max_m);
    if (planning_samples > 0) {
      views.push_back(DepthView{*frame.T_G_C * depth.T_B_D, depth.intrinsics, info.depth_min_m,
                                info.depth_max_m,
                                variants.front()->mapper->config().integrator.max_ray_length_m});
    }
    const bool ok = r.state == TrackingState::kOk && r.T_C_G.has_value();
    if (!ok) ++lost;
    for (auto& v : variants) {
      TimedPose pose;
      pose.utime = utime;
      if (v->kind == Kind::kGroundTruth) {
        pose.T_G_C = *frame.T_G_C;
      } else {
        if (!ok) {
          if (v->kind == Kind::kNaive) continue;  // nothing to integrate with
          pose.tracking_ok = false;
        } else {
          pose.T_G_C = r.T_C_G->inverse();
          pose.jump = v->kind != Kind::kNaive && (r.relocalized || r.map_corrected);
          pose.reference_keyframe = r.reference_keyframe;  // epoch 0: keys are the ids
        }
      }
      v->mapper->onFramePose(pose);
      v->mapper->onDepthFrame(depth);
    }
    if (sync_slam) {
      settle();
    } else {
      waitAll();
    }
    ++n;
    if (n % 50 == 0) {
      const double s = std::chrono::duration<double>(Clock::now() - start).count();
      std::fprintf(stderr,
                   "frame %zu/%zu, %.1f frames/s, ETA %.0f s, %zu keyframes, "
                   "subvolumes:",
                   n, total, n / s, total > n ? (total - n) * s / n : 0.0,
                   slam.map().numKeyframes());
      for (auto& v : variants) std::fprintf(stderr, " %zu", v->mapper->collection().size());
      std::fprintf(stderr, "\n");
    }
  }
  std::fprintf(stderr, "\n");
  slam.waitUntilIdle();
  deliver();
  waitAll();
  // Requests and fusions still in flight settle (replies arrive within the services' time).
  std::this_thread::sleep_for(std::chrono::seconds(3));
  waitAll();
  // The drive is over but maintenance is not: on the input clock nothing asks the pairs that
  // became free after the last input (the last subvolume finished, a fusion done), which the
  // steady clock's 0.25 s tick would. Tick every mapper until a round changes no count.
  auto fusionProgress = [&] {
    uint64_t sum = 0;
    for (auto& v : variants) sum += v->mapper->status().fusion.progress();
    return sum;
  };
  size_t end_rounds = 0;
  for (uint64_t before = fusionProgress(); end_rounds < 100; ++end_rounds) {
    for (auto& v : variants) v->mapper->maintenanceTick();
    settle();
    const uint64_t after = fusionProgress();
    if (after == before) break;
    before = after;
  }
  std::fprintf(stderr, "after the last frame: %zu maintenance rounds changed the fusions\n",
               end_rounds);
  slam.stop();
  for (auto& v : variants) {
    if (v->covariance) v->covariance->stop();
  }
  waitAll();

  // Evaluation against the exact scene.
  const BuiltinScene truth_scene = makeBuiltinScene(scene);
  const auto raycaster = TriangleMeshRaycaster::create(truth_scene.mesh, &error);
  if (!raycaster) {
    std::fprintf(stderr, "ground truth: %s\n", error.c_str());
    return 1;
  }
  MeshAccuracyConfig accuracy_options;
  accuracy_options.max_surface_samples = 200000;
  // The tracker's frame G starts at the first frame's true pose but its gauge drifts; maps
  // built with its poses are compared after the SE(3) alignment of the final keyframe
  // positions to the true ones (as ATE is).
  std::vector<Eigen::Vector3d> estimated, true_positions;
  for (const Keyframe* k : slam.map().keyframes()) {
    const auto it = truth_by_frame.find(k->frame_id);
    if (it == truth_by_frame.end()) continue;
    estimated.push_back(k->T_G_C().translation());
    true_positions.push_back(it->second.translation());
  }
  const std::optional<Alignment> alignment =
      umeyamaAlign(estimated, true_positions, AlignmentType::kSE3, &error);
  if (!alignment) std::fprintf(stderr, "alignment: %s (maps compared unaligned)\n", error.c_str());
  if (planning_samples > 0) {
    scorePlanningMaps(*raycaster, views, planning_samples, voxel,
                      alignment ? std::optional<Transformationd>(alignment->T_A_B) : std::nullopt,
                      &variants);
  }
  for (auto& v : variants) {
    accuracy_options.T_G_R.reset();
    if (v->kind != Kind::kGroundTruth && alignment) accuracy_options.T_G_R = *alignment;
    const MapperConfig& config = v->mapper->config();
    const Mesh mesh = meshCollection(v->mapper->collection(), config.layer, config.fusion,
                                     config.mesh, /*include_active=*/true);
    v->subvolumes = v->mapper->collection().size();
    v->blocks = v->mapper->collection().numBlocks();
    v->vertices = mesh.numVertices();
    v->fusion = v->mapper->status().fusion;
    const auto accuracy = evaluateMeshAccuracy(*raycaster, mesh, accuracy_options, &error);
    if (accuracy) {
      v->rmse_m = accuracy->accuracy_m.rmse;
      v->median_m = accuracy->accuracy_m.median;
    } else {
      std::fprintf(stderr, "%s: %s\n", v->name.c_str(), error.c_str());
    }
    v->mapper->stop();
  }
  std::filesystem::remove_all(work);

  // The covisibility graphs the fusion candidates came from, at the end (what is left unfused).
  for (const auto& v : variants) {
    if (v->kind != Kind::kOn) continue;
    // The strongest only: the town leaves hundreds.
    constexpr size_t kShown = 20;
    const std::vector<CovisibilityCandidate> edges = v->mapper->covisibilityEdges();
    std::printf("%s: %zu covisibility edges left (shared / |L_a| / |L_b|), the strongest:",
                v->name.c_str(), edges.size());
    for (size_t i = 0; i < std::min(edges.size(), kShown); ++i) {
      const CovisibilityCandidate& e = edges[i];
      std::printf(" %lld-%lld %d/%zu/%zu", static_cast<long long>(e.a), static_cast<long long>(e.b),
                  e.shared, e.landmarks_a, e.landmarks_b);
    }
    std::printf("\n");
  }
  {
    std::lock_guard<std::mutex> lock(errors_mutex);
    std::sort(build_ms.begin(), build_ms.end());
    if (!build_ms.empty()) {
      std::printf(
          "covariance requests: %zu (%zu from a kept linearization), time per request median "
          "%.1f ms, max %.0f ms\n",
          build_ms.size(), reused, build_ms[build_ms.size() / 2], build_ms.back());
    }
    for (const auto& [message, count] : errors) {
      std::printf("covariance error x%d: %s\n", count, message.c_str());
    }
  }
  for (const auto& v : variants) {
    if (v->kind != Kind::kOn) continue;
    std::lock_guard<std::mutex> lock(v->pairs_mutex);
    std::vector<double> q, distance, shared;
    size_t certain = 0;
    for (const PairAnswer& a : v->answers) {
      if (!a.ok) continue;
      q.push_back(a.q);
      distance.push_back(a.distance_m);
      shared.push_back(a.keyframe_shared);
      if (a.q >= v->q_min) ++certain;
    }
    std::printf(
        "%s: %zu pairs answered (%s keyframes): q median %.3g, %zu (%.0f %%) >= q_min; "
        "distance between the keyframes median %.2f m; landmarks both saw median %.0f\n",
        v->name.c_str(), q.size(), pairKeyframesName(v->pair_keyframes), quantile(&q, 0.5), certain,
        q.empty() ? 0.0 : 100.0 * static_cast<double>(certain) / static_cast<double>(q.size()),
        quantile(&distance, 0.5), quantile(&shared, 0.5));
  }
  const Variant& gt = *variants[0];
  const Variant& off = *variants[2];
  // How the off map's subvolumes cover the run: a revisit that adds few keyframes shows as
  // one subvolume with few keyframes and many blocks.
  std::printf("off subvolumes (id: keyframes, blocks, farthest keyframe from the anchor):");
  for (const std::shared_ptr<Submap>& submap : off.mapper->collection().submaps()) {
    double farthest = 0.0;
    {
      std::lock_guard<std::mutex> lock(positions_mutex);
      const auto anchor = keyframe_positions.find(submap->anchorKeyframe());
      for (const KeyframeId k : submap->keyframeIds()) {
        const auto it = keyframe_positions.find(k);
        if (anchor != keyframe_positions.end() && it != keyframe_positions.end()) {
          farthest = std::max(farthest, (it->second - anchor->second).norm());
        }
      }
    }
    std::printf(" %lld: %zu, %zu, %.1f m;", static_cast<long long>(submap->id()),
                submap->numKeyframes(), submap->numBlocks(), farthest);
  }
  std::printf("\n");
  // What the other subvolume maps end with: which anchors are left apart.
  for (const auto& v : variants) {
    if (v.get() == &off || (v->kind != Kind::kOff && v->kind != Kind::kOn)) continue;
    std::printf("%s subvolumes (id: anchor keyframe, keyframes, blocks):", v->name.c_str());
    for (const std::shared_ptr<Submap>& submap : v->mapper->collection().submaps()) {
      std::printf(" %lld: %lld, %zu, %zu;", static_cast<long long>(submap->id()),
                  static_cast<long long>(submap->anchorKeyframe()), submap->numKeyframes(),
                  submap->numBlocks());
    }
    std::printf("\n");
  }
  std::printf(
      "scene %s, %s x%d, %zu frames (%zu not tracked), %zu keyframes, %llu loops closed, voxel "
      "%.3f m, "
      "%s depth, depth noise %.4f z^2, %d keyframes per subvolume, SLAM %s; alignment of the "
      "tracker's frame: %.1f mm, %.3f deg\n",
      scene.c_str(), trajectory.c_str(), laps, n, lost, slam.map().numKeyframes(),
      static_cast<unsigned long long>(slam.loopClosingStats().loops_closed), voxel,
      depth_kind.c_str(), depth_noise, keyframes_per_subvolume,
      sync_slam ? "waited for per frame" : "in real time",
      alignment ? 1e3 * alignment->T_A_B.translation().norm() : 0.0,
      alignment ? alignment->T_A_B.rotation().angularDistance(Eigen::Quaterniond::Identity()) *
                      180.0 / M_PI
                : 0.0);
  std::printf(
      "| map | subvolumes | blocks | size / OFF | RMSE (mm) | RMSE / GT | median (mm) | "
      "candidates | requested | fused (same anchor) | rejected by q | errors / timed out / late "
      "replies used / ignored |\n");
  std::printf("|---|---|---|---|---|---|---|---|---|---|---|---|\n");
  for (const auto& v : variants) {
    std::printf(
        "| %s | %zu | %zu | %.0f %% | %.1f | %.2f | %.2f | %llu | %llu | %llu (%llu) | %llu | "
        "%llu / %llu / %llu / %llu |\n",
        v->name.c_str(), v->subvolumes, v->blocks,
        100.0 * static_cast<double>(v->blocks) / static_cast<double>(off.blocks), 1e3 * v->rmse_m,
        v->rmse_m / gt.rmse_m, 1e3 * v->median_m,
        static_cast<unsigned long long>(v->fusion.candidates),
        static_cast<unsigned long long>(v->fusion.requested),
        static_cast<unsigned long long>(v->fusion.fused),
        static_cast<unsigned long long>(v->fusion.same_anchor),
        static_cast<unsigned long long>(v->fusion.rejected_by_q),
        static_cast<unsigned long long>(v->fusion.covariance_errors),
        static_cast<unsigned long long>(v->fusion.requests_timed_out),
        static_cast<unsigned long long>(v->fusion.late_replies),
        static_cast<unsigned long long>(v->fusion.replies_ignored));
  }

  if (!out_dir.empty()) {
    // maintenance_<scene>[_<trajectory>]: the loop keeps the names of earlier runs.
    const std::string stem = trajectory == "loop" ? scene : scene + "_" + trajectory;
    std::filesystem::create_directories(out_dir);
    nlohmann::ordered_json json = {{"scene", scene},
                                   {"trajectory", trajectory},
                                   {"laps", static_cast<size_t>(laps)},
                                   {"frames", n},
                                   {"keyframes", slam.map().numKeyframes()},
                                   {"voxel_m", voxel},
                                   {"depth", depth_kind},
                                   {"depth_noise_per_m2", depth_noise},
                                   {"tracker_config", config_path},
                                   {"maps", nlohmann::ordered_json::array()}};
    for (const auto& v : variants) {
      json["maps"].push_back({{"name", v->name},
                              {"q_min", v->q_min},
                              {"pair_keyframes", pairKeyframesName(v->pair_keyframes)},
                              {"revisit_anchor_distance_m", v->revisit_m},
                              {"revisit_after_frames", v->revisit_frames},
                              {"subvolumes", v->subvolumes},
                              {"blocks", v->blocks},
                              {"rmse_m", v->rmse_m},
                              {"median_m", v->median_m},
                              {"candidates", v->fusion.candidates},
                              {"requested", v->fusion.requested},
                              {"fused", v->fusion.fused},
                              {"fused_same_anchor", v->fusion.same_anchor},
                              {"rejected_by_q", v->fusion.rejected_by_q}});
      if (v->planning) {
        const DistanceFieldAccuracy& a = *v->planning;
        json["maps"].back()["planning"] = {{"samples", a.samples},
                                           {"field_blocks", v->planning_stats.blocks},
                                           {"band_blocks", v->planning_stats.band_blocks},
                                           {"field_bytes", v->planning_stats.memory_bytes},
                                           {"answered_free", a.answered_free},
                                           {"answered_occupied", a.answered_occupied},
                                           {"answered_unknown", a.answered_unknown},
                                           {"error_median_voxels", a.error_median_voxels},
                                           {"error_p99_voxels", a.error_p99_voxels},
                                           {"error_max_voxels", a.error_max_voxels},
                                           {"compared_seen", a.compared_seen},
                                           {"seen_error_median_voxels", a.seen_error_median_voxels},
                                           {"seen_error_p99_voxels", a.seen_error_p99_voxels},
                                           {"seen_error_max_voxels", a.seen_error_max_voxels},
                                           {"near_obstacle", a.near_obstacle},
                                           {"unsafe", a.unsafe},
                                           {"unsafe_seen", a.unsafe_seen},
                                           {"unsafe_seen_by_a_voxel", a.unsafe_seen_by_a_voxel},
                                           {"unsafe_by_a_voxel", a.unsafe_by_a_voxel},
                                           {"observed_free", a.observed_free},
                                           {"observed_free_unknown", a.observed_free_unknown},
                                           {"far_answered_occupied", a.far_answered_occupied}};
      }
    }
    std::ofstream(out_dir + "/maintenance_" + stem + ".json") << json.dump(2) << "\n";
    ScatterPlotConfig plot;
    plot.title = "map maintenance on " + scene + ": size vs accuracy";
    plot.x_label = "map size [TSDF blocks]";
    plot.y_label = "vertex RMSE [mm]";
    // Variants that end with the same map share one marker and one label.
    std::vector<ScatterPoint> points;
    for (const auto& v : variants) {
      const ScatterPoint point{static_cast<double>(v->blocks), 1e3 * v->rmse_m, v->name,
                               v->kind == Kind::kOn ? 1 : 0};
      auto same = std::find_if(points.begin(), points.end(), [&](const ScatterPoint& p) {
        return p.x == point.x && p.y == point.y && p.series == point.series;
      });
      if (same == points.end()) {
        points.push_back(point);
      } else {
        same->label += ", " + point.label.substr(point.label.find('>') + 2);
      }
    }
    const std::string path = out_dir + "/maintenance_" + stem + "_sweep.png";
    if (!writeScatterPlotPng(path, points, plot, &error)) {
      std::fprintf(stderr, "%s\n", error.c_str());
    } else {
      std::printf("wrote %s\n", path.c_str());
    }
  }
  return 0;
}

}  // namespace
}  // namespace cblox

int main(int argc, char** argv) { return cblox::run(argc, argv); }
