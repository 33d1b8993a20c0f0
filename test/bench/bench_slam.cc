// Sparse SLAM benchmark and evaluation on the simulator: runs the whole system (tracking on
// this thread, local mapping and loop closing on theirs) over a built-in scene's trajectory
// and reports what issue 4 asks for: tracking time per frame (features + tracking, median
// and p95; of the tracking, the time spent waiting for the map's lock), local BA and
// loop-correction times, CPU use of the process, loops detected / false loops, and ATE (Umeyama
// SE(3)) of the frame poses as published and of the final keyframe poses, before the first loop
// closure and at the end.
//
//   cblox-bench-slam [--scene room|hall|town | --source SPEC] [--trajectory loop] [--laps 2]
//                    [--frames N] [--rate HZ] [--one-core] [--vocabulary FILE]
//                    [--config TRACKER_YAML] [--capture-config CAPTURE_YAML] [--out DIR]
//                    [--up AXIS]
//
// --capture-config takes a capture.yaml's source settings (the simulator's rig, noise and
// rate, e.g. config/examples/sim_kitti_rig.yaml) instead of the defaults; its source: is
// not used (--scene / --source say what plays).
// --source plays a recorded stereo source with ground truth on every frame instead of a
// scene (kitti:DIR, euroc:DIR); its folder's name takes the scene's place in the outputs.
//
// Frames are rendered first (progress printed), then fed at --rate (default: the source's
// rate, so local mapping gets real-time slack; 0 = as fast as possible). --one-core
// extracts the left and right images on the tracking thread (the "one core" figure).
// --config takes the SLAM settings (frames, tracker, local_mapping, loop_closing, ...) of a
// tracker.yaml instead of the defaults, so a setting can be measured before it is shipped.
// --out writes DIR/slam_<scene>.json and DIR/slam_<scene>_trajectory.png, a top view: the
// plane orthogonal to --up (default z for the simulator's z-up world, -y for a --source,
// whose world is its first camera's frame, y down).
// A loop is "false" when the constraint it added is wrong: the final estimated pose of the
// query keyframe relative to the candidate differs from the true relative pose by more than
// 0.5 m or 5 degrees. (Two keyframes metres apart that see the same street are a true loop;
// the bench prints their true distance and viewing angle too.)

#include <sys/resource.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <map>
#include <mutex>
#include <optional>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include <CLI/CLI.hpp>
#include <nlohmann/json.hpp>

#include "core/eval/trajectory_metrics.h"
#include "core/eval/mesh_height.h"
#include "core/eval/trajectory_plot.h"
#include "core/io/tum_trajectory.h"
#include "core/tracking/slam_system.h"
#include "daemon/capture/capture_config.h"
#include "daemon/common/cli.h"
#include "daemon/common/yaml_config.h"
#include "daemon/tracker/tracker_config.h"
#include "daemon/tracker/tracker_node.h"
#include "drivers/open_frame_source.h"

namespace cblox {
namespace {

using Clock = std::chrono::steady_clock;

double percentile(std::vector<double> v, double p) {
  if (v.empty()) return 0.0;
  std::sort(v.begin(), v.end());
  return v[std::min(v.size() - 1,
                    static_cast<size_t>(p * static_cast<double>(v.size() - 1) + 0.5))];
}

double cpuSeconds() {
  rusage usage{};
  getrusage(RUSAGE_SELF, &usage);
  return static_cast<double>(usage.ru_utime.tv_sec + usage.ru_stime.tv_sec) +
         1e-6 * static_cast<double>(usage.ru_utime.tv_usec + usage.ru_stime.tv_usec);
}

struct Ate {
  double rmse = 0.0, max = 0.0;
  size_t count = 0;
  /// Of a Sim(3) alignment of the same pairs: the scale mapping the estimate onto the truth
  /// (> 1: the estimate is too small) and the RMSE left after it.
  double sim3_scale = 1.0, sim3_rmse = 0.0;
};

Ate ate(const StampedTrajectory& truth, const StampedTrajectory& estimate) {
  Ate result;
  if (estimate.size() < 3) return result;
  std::string error;
  const auto pairs = associateTrajectories(truth, estimate, AssociationConfig{});
  const auto a = computeAte(pairs, AlignmentType::kSE3, &error);
  if (!a) return result;
  result.rmse = a->translation_m.rmse;
  result.max = a->translation_m.max;
  result.count = a->translation_m.count;
  if (const auto s = computeAte(pairs, AlignmentType::kSim3, &error)) {
    result.sim3_scale = s->alignment.scale;
    result.sim3_rmse = s->translation_m.rmse;
  }
  return result;
}

int run(int argc, char** argv) {
  std::string scene = "room", trajectory = "loop", vocabulary_path, out_dir, config_path,
              source_spec, capture_config_path, up_text;
  int laps = 2;
  size_t max_frames = 0;
  double rate = -1.0;
  bool one_core = false;
#ifdef CBLOX_DEFAULT_VOCABULARY
  vocabulary_path = CBLOX_DEFAULT_VOCABULARY;
#endif
  CLI::App app{
      "cblox-bench-slam: the sparse SLAM on a simulated scene: tracking, local BA and loop times,\n"
      "CPU, loops (false ones too) and ATE.",
      "cblox-bench-slam"};
  app.add_option("--scene", scene, "room | hall | town")->capture_default_str();
  app.add_option("--source", source_spec,
                 "a recorded stereo source with ground truth on every frame, instead of --scene "
                 "(kitti:DIR, euroc:DIR)")
      ->type_name("SPEC");
  app.add_option("--trajectory", trajectory, "trajectory kind")->capture_default_str();
  app.add_option("--laps", laps, "laps of the trajectory")->capture_default_str();
  app.add_option("--frames", max_frames, "frames at the most (0: all)")->capture_default_str();
  app.add_option("--rate", rate, "frames fed per second (default: the source's; 0: no wait)");
  app.add_flag("--one-core", one_core, "extract both images on the tracking thread");
  app.add_option("--vocabulary", vocabulary_path, "vocabulary file")->capture_default_str();
  app.add_option("--config", config_path,
                 "a tracker.yaml: its SLAM settings replace the defaults (camera settings unused)")
      ->type_name("FILE");
  app.add_option("--capture-config", capture_config_path,
                 "a capture.yaml: its source settings (simulator rig, noise, rate) replace the "
                 "defaults")
      ->type_name("FILE");
  app.add_option("--out", out_dir,
                 "writes DIR/slam_<scene>.json, the trajectory picture, per-frame rows "
                 "(_frames.csv) and the final keyframes with the truth at their times "
                 "(_keyframes.tum, _keyframes_truth.tum)")
      ->type_name("DIR");
  app.add_option("--up", up_text,
                 "the world's up axis for the trajectory picture: x, y, z, -x, -y or -z (default "
                 "z for --scene, -y for --source)")
      ->type_name("AXIS");
  if (const std::optional<int> code = parseCommandLine(app, argc, argv)) return *code;
  if (up_text.empty()) up_text = source_spec.empty() ? "z" : "-y";
  const std::optional<Eigen::Vector3d> up = parseUpAxis(up_text);
  if (!up) {
    std::fprintf(stderr, "--up: expected x, y, z, -x, -y or -z, got \"%s\"\n", up_text.c_str());
    return 2;
  }
  std::string error;
  const auto vocabulary = BinaryVocabulary::load(vocabulary_path, &error);
  if (!vocabulary) {
    std::fprintf(stderr, "vocabulary: %s\n", error.c_str());
    return 2;
  }
  SourceConfig options;
  if (!capture_config_path.empty()) {
    try {
      options = loadCaptureConfig(loadYamlFile(capture_config_path)).source_config;
    } catch (const std::exception& e) {
      std::fprintf(stderr, "%s: %s\n", capture_config_path.c_str(), e.what());
      return 2;
    }
  }
  options.trajectory = trajectory;
  options.laps = laps;
  options.max_frames = max_frames;
  auto source = openFrameSource(source_spec.empty() ? "sim:" + scene : source_spec, options, &error);
  if (!source) {
    std::fprintf(stderr, "%s\n", error.c_str());
    return 2;
  }
  const SourceInfo info = source->info();
  if (!info.stereo) {
    std::fprintf(stderr, "%s: not a stereo source\n", info.name.c_str());
    return 2;
  }
  if (!source_spec.empty()) {
    // The run's name in the outputs: the source folder's ("kitti:/d/seq/" gives "seq").
    const std::filesystem::path folder =
        std::filesystem::path(source_spec.substr(source_spec.find(':') + 1)).lexically_normal();
    scene = (folder.has_filename() ? folder : folder.parent_path()).filename().string();
  }
  if (rate < 0.0) rate = info.rate_hz;
  // Render everything first, so that rendering does not compete with SLAM for the cores.
  std::vector<CaptureFrame> frames;
  const auto render_start = Clock::now();
  CaptureFrame frame;
  for (FrameSource::Status status; (status = source->next(&frame, &error)) !=
                                   FrameSource::Status::kEnd;) {
    if (status != FrameSource::Status::kFrame) {
      std::fprintf(stderr, "%s: %s\n", info.name.c_str(), error.c_str());
      return 1;
    }
    if (!frame.T_G_C) {
      std::fprintf(stderr, "%s: frame %lld has no ground truth\n", info.name.c_str(),
                   static_cast<long long>(frame.frame_id));
      return 2;
    }
    frame.depth = DepthImage();  // stereo SLAM: only the grey pair is kept
    frame.color = ColorImage();
    frames.push_back(std::move(frame));
    if (frames.size() % 100 == 0) {
      std::fprintf(stderr, "\rrendered %zu frames (%.1f s)", frames.size(),
                   std::chrono::duration<double>(Clock::now() - render_start).count());
    }
  }
  std::fprintf(stderr, "\rrendered %zu frames\n", frames.size());

  const std::optional<TrackerNodeConfig> node = loadTrackerNodeSettings(config_path, &error);
  if (!node) {
    std::fprintf(stderr, "%s\n", error.c_str());
    return 2;
  }
  const RectifiedStereoCalibration& calibration = *info.stereo;
  const TrackingCamera camera = makeTrackingCamera(calibration.intrinsics, calibration.baseline_m,
                                                   node->close_depth_baselines);
  SlamSystemConfig config = node->slam;
  if (one_core) config.frames.parallel_stereo_extraction = false;
  // The SLAM threads at the niceness cblox-tracker gives them (tracker.yaml's
  // local_mapping.niceness and loop_closing.niceness).
  SlamSystem slam(camera, config, &*vocabulary,
                  slamThreadPriorities(*node, [](const std::string& line) {
                    std::fprintf(stderr, "%s\n", line.c_str());
                  }));
  std::mutex mutex;
  std::vector<LoopClosureEvent> loops;
  std::vector<double> ba_ms;
  // The sampled local BAs' sizes: free and fixed keyframes, landmarks, observations.
  std::vector<double> ba_free, ba_fixed, ba_landmarks, ba_observations;
  slam.setLoopCallback([&](const LoopClosureEvent& e) {
    std::lock_guard<std::mutex> lock(mutex);
    loops.push_back(e);
  });

  StampedTrajectory truth, online, before_loop;
  std::map<uint64_t, Transformationd> truth_by_frame;
  std::vector<double> frame_ms, track_ms, wait_ms;
  std::map<std::string, size_t> keyframe_reasons;  // keyframes made, by KeyframeReason
  // Inliers of every tracked frame, and of the frames that made a keyframe, by reason.
  std::vector<double> inliers;
  std::map<std::string, std::vector<double>> keyframe_inliers;
  // Frame times of the frames that made a keyframe and of the others.
  std::vector<double> keyframe_frame_ms, other_frame_ms;
  // One row per frame for --out's slam_<scene>_frames.csv: where a lost stretch began and
  // how the inliers fell before it.
  std::ostringstream frame_rows;
  frame_rows << "frame,state,inliers,keyframe_reason,reference_keyframe\n";
  size_t lost = 0;
  TrackingState last_state = TrackingState::kNotInitialized;
  const double cpu_start = cpuSeconds();
  const auto start = Clock::now();
  uint64_t last_ba = 0;
  for (size_t i = 0; i < frames.size(); ++i) {
    const CaptureFrame& f = frames[i];
    if (rate > 0.0) {
      std::this_thread::sleep_until(start + std::chrono::duration_cast<Clock::duration>(
                                                std::chrono::duration<double>(i / rate)));
    }
    const double t = static_cast<double>(f.timestamp_ns) * 1e-9;
    truth.push_back({t, *f.T_G_C});
    truth_by_frame[static_cast<uint64_t>(f.frame_id)] = *f.T_G_C;
    const auto frame_start = Clock::now();
    const TrackingResult r = slam.trackStereo(static_cast<uint64_t>(f.frame_id), f.timestamp_ns,
                                              f.left, f.right, f.T_G_C->inverse());
    frame_ms.push_back(
        std::chrono::duration<double, std::milli>(Clock::now() - frame_start).count());
    track_ms.push_back(r.time_ms);
    wait_ms.push_back(r.map_wait_ms);
    (r.new_keyframe != nullptr ? keyframe_frame_ms : other_frame_ms).push_back(frame_ms.back());
    if (r.new_keyframe != nullptr) {
      ++keyframe_reasons[keyframeReasonName(r.keyframe_reason)];
      keyframe_inliers[keyframeReasonName(r.keyframe_reason)].push_back(r.inliers);
    }
    if (r.state == TrackingState::kOk) inliers.push_back(r.inliers);
    frame_rows << i << ',' << trackingStateName(r.state) << ',' << r.inliers << ','
               << (r.new_keyframe != nullptr ? keyframeReasonName(r.keyframe_reason) : "") << ','
               << r.reference_keyframe << '\n';
    if (r.state != last_state || r.relocalized) {
      // Every change of state, with the tracker's reason, so a lost stretch can be found.
      std::fprintf(stderr, "\nframe %zu: %s%s%s%s\n", i, trackingStateName(r.state),
                   r.relocalized ? " (relocalized)" : "", r.reason.empty() ? "" : ": ",
                   r.reason.c_str());
      last_state = r.state;
    }
    if (r.state != TrackingState::kOk) {
      ++lost;
    } else {
      online.push_back({t, r.T_C_G->inverse()});
      bool looped;
      {
        std::lock_guard<std::mutex> lock(mutex);
        looped = !loops.empty();
      }
      if (!looped) before_loop.push_back({t, r.T_C_G->inverse()});
    }
    const LocalMapperStats ls = slam.localMappingStats();
    if (ls.bundle_adjustments != last_ba) {
      last_ba = ls.bundle_adjustments;
      ba_ms.push_back(ls.last_ba_ms);
      ba_free.push_back(static_cast<double>(ls.last_ba_free_keyframes));
      ba_fixed.push_back(static_cast<double>(ls.last_ba_fixed_keyframes));
      ba_landmarks.push_back(static_cast<double>(ls.last_ba_landmarks));
      ba_observations.push_back(static_cast<double>(ls.last_ba_observations));
    }
    if ((i + 1) % 100 == 0 || i + 1 == frames.size()) {
      const double elapsed = std::chrono::duration<double>(Clock::now() - start).count();
      std::fprintf(stderr, "\rframe %zu/%zu (%.1f Hz), %zu keyframes, %zu loops, ETA %.0f s   ",
                   i + 1, frames.size(), (i + 1) / elapsed, slam.map().numKeyframes(), loops.size(),
                   elapsed / (i + 1) * (frames.size() - i - 1));
    }
  }
  slam.waitUntilIdle();
  const double wall_s = std::chrono::duration<double>(Clock::now() - start).count();
  const double cpu_s = cpuSeconds() - cpu_start;
  slam.stop();
  std::fprintf(stderr, "\n");

  // Final keyframe trajectory and path length.
  StampedTrajectory keyframes_truth, keyframes_final;
  for (const Keyframe* k : slam.map().keyframes()) {
    const double t = static_cast<double>(k->timestamp_ns) * 1e-9;
    keyframes_final.push_back({t, k->T_G_C()});
    keyframes_truth.push_back({t, truth_by_frame.at(k->frame_id)});
  }
  double path = 0.0;
  for (size_t i = 1; i < truth.size(); ++i) {
    path += (truth[i].T_G_C.translation() - truth[i - 1].T_G_C.translation()).norm();
  }
  size_t false_loops = 0;
  for (const LoopClosureEvent& e : loops) {
    const Keyframe* q = slam.map().keyframe(e.query);
    const Keyframe* c = slam.map().keyframe(e.candidate);
    const Transformationd& tq = truth_by_frame.at(q->frame_id);
    const Transformationd& tc = truth_by_frame.at(c->frame_id);
    const double distance = (tq.translation() - tc.translation()).norm();
    const double angle = std::acos(
        std::clamp((tq.rotationMatrix().col(2)).dot(tc.rotationMatrix().col(2)), -1.0, 1.0));
    // The error of the final relative pose candidate -> query against the true one.
    const Transformationd relative_error =
        (c->T_G_C().inverse() * q->T_G_C()).inverse() * (tc.inverse() * tq);
    const double error_m = relative_error.translation().norm();
    const double error_deg =
        relative_error.rotation().angularDistance(Eigen::Quaterniond::Identity()) * 180.0 / M_PI;
    const bool is_false = error_m > 0.5 || error_deg > 5.0;
    if (is_false) ++false_loops;
    std::printf(
        "  loop: keyframe of frame %lu to keyframe of frame %lu: true centres %.2f m, "
        "viewing directions %.1f deg apart; final relative pose off by %.3f m, %.2f deg%s\n",
        static_cast<unsigned long>(q->frame_id), static_cast<unsigned long>(c->frame_id), distance,
        angle * 180.0 / M_PI, error_m, error_deg, is_false ? " (FALSE)" : "");
  }
  const Ate ate_online = ate(truth, online), ate_before = ate(truth, before_loop),
            ate_keyframes = ate(truth, keyframes_final);
  const LoopCloserStats lc = slam.loopClosingStats();
  std::vector<double> correction_ms, graph_ms, locked_ms;
  for (const auto& e : loops) {
    correction_ms.push_back(e.correction_ms);
    graph_ms.push_back(e.graph_ms);
    locked_ms.push_back(e.locked_ms);
  }

  std::printf("scene %s/%s x%d: %zu frames (%.1f m), %zu lost, %zu keyframes\n", scene.c_str(),
              trajectory.c_str(), laps, frames.size(), path, lost, slam.map().numKeyframes());
  std::printf(
      "  per frame (features + tracking): median %.1f ms, p95 %.1f ms; tracking alone "
      "median %.1f ms%s\n",
      percentile(frame_ms, 0.5), percentile(frame_ms, 0.95), percentile(track_ms, 0.5),
      one_core ? " (one core)" : " (left/right extraction on 2 threads)");
  std::printf(
      "  frames that made a keyframe: %zu, median %.1f ms, p95 %.1f ms; the others: median %.1f "
      "ms, p95 %.1f ms\n",
      keyframe_frame_ms.size(), percentile(keyframe_frame_ms, 0.5),
      percentile(keyframe_frame_ms, 0.95), percentile(other_frame_ms, 0.5),
      percentile(other_frame_ms, 0.95));
  double wait_sum = 0.0;
  for (const double w : wait_ms) wait_sum += w;
  std::printf(
      "  of which waiting for the map's lock (local mapping or loop closing held it): median "
      "%.2f ms, p95 %.2f ms, mean %.2f ms\n",
      percentile(wait_ms, 0.5), percentile(wait_ms, 0.95),
      wait_ms.empty() ? 0.0 : wait_sum / static_cast<double>(wait_ms.size()));
  const LocalMapperStats lm = slam.localMappingStats();
  std::printf("  keyframes made by reason:");
  for (const auto& [name, count] : keyframe_reasons) std::printf(" %s %zu", name.c_str(), count);
  std::printf(" (none: the first); culled %lu\n", static_cast<unsigned long>(lm.keyframes_culled));
  std::printf("  inliers of tracked frames: median %.0f, p5 %.0f; of the frames that made",
              percentile(inliers, 0.5), percentile(inliers, 0.05));
  for (const auto& [name, values] : keyframe_inliers) {
    std::printf(" %s %.0f (p5 %.0f)", name.c_str(), percentile(values, 0.5),
                percentile(values, 0.05));
  }
  std::printf(" keyframes\n");
  std::printf(
      "  local BA: %zu runs (%lu in all, %lu interrupted by the tracker), median %.1f ms, p95 "
      "%.1f ms; median size %.0f keyframes optimised + %.0f fixed, %.0f landmarks, %.0f "
      "observations (p95 %.0f)\n",
      ba_ms.size(), static_cast<unsigned long>(lm.bundle_adjustments),
      static_cast<unsigned long>(lm.bundle_adjustments_aborted), percentile(ba_ms, 0.5),
      percentile(ba_ms, 0.95), percentile(ba_free, 0.5), percentile(ba_fixed, 0.5),
      percentile(ba_landmarks, 0.5), percentile(ba_observations, 0.5),
      percentile(ba_observations, 0.95));
  const LocalMapperStats::StepSeconds& steps = lm.cpu_s;
  std::printf(
      "  local mapping CPU: %.1f s in all: refresh %.1f, landmark culling %.1f, triangulation "
      "%.1f, fusion %.1f, local BA %.1f, keyframe culling %.1f s\n",
      steps.total(), steps.refresh, steps.cull_landmarks, steps.triangulate, steps.fuse,
      steps.bundle_adjustment, steps.cull_keyframes);
  const DisparityCorrectionStats dc = slam.disparityCorrectionStats();
  std::printf(
      "  disparity correction: %.2f px in use (%lu updates; %lu window estimates, last %.2f px, "
      "spread %.2f px; %lu solves without one, %lu refused); its solves %.2f s CPU\n",
      dc.correction_px, static_cast<unsigned long>(dc.updates),
      static_cast<unsigned long>(dc.estimates), dc.last_estimate_px, dc.spread_px,
      static_cast<unsigned long>(lm.disparity_offset_failures),
      static_cast<unsigned long>(dc.refused), lm.disparity_offset_seconds);
  std::printf(
      "  loops: %zu closed (%zu false), %lu rejected after verification (%lu candidates by "
      "the drift gate); correction median %.1f ms (essential graph %.1f ms, the map locked "
      "%.1f ms); global BA %lu (last %.0f ms, on its own thread; %lu abandoned)\n",
      loops.size(), false_loops, static_cast<unsigned long>(lc.loops_rejected),
      static_cast<unsigned long>(lc.loops_rejected_drift), percentile(correction_ms, 0.5),
      percentile(graph_ms, 0.5), percentile(locked_ms, 0.5),
      static_cast<unsigned long>(lc.global_bundle_adjustments), lc.last_global_ba_ms,
      static_cast<unsigned long>(lc.global_bundle_adjustments_abandoned));
  std::printf("  CPU: %.2f cores over %.1f s\n", cpu_s / wall_s, wall_s);
  std::printf(
      "  ATE RMSE: frames before the first loop %.4f m (%.2f %% of path), all frames as "
      "published %.4f m, final keyframes %.4f m (%.3f %% of path)\n",
      ate_before.rmse, 100.0 * ate_before.rmse / path, ate_online.rmse, ate_keyframes.rmse,
      100.0 * ate_keyframes.rmse / path);
  // A map uniformly too small or too large (stereo depth bias) shows as a scale far from 1
  // with a small RMSE left after the Sim(3) alignment.
  std::printf("  final keyframes aligned with scale: scale %.4f, ATE RMSE %.4f m\n",
              ate_keyframes.sim3_scale, ate_keyframes.sim3_rmse);

  if (!out_dir.empty()) {
    std::filesystem::create_directories(out_dir);
    const nlohmann::ordered_json json = {
        {"scene", scene},
        {"trajectory", trajectory},
        {"laps", static_cast<size_t>(laps)},
        {"frames", frames.size()},
        {"path_m", path},
        {"lost", lost},
        {"keyframes", slam.map().numKeyframes()},
        {"keyframe_reasons", keyframe_reasons},
        {"one_core", one_core},
        {"frame_ms_median", percentile(frame_ms, 0.5)},
        {"frame_ms_p95", percentile(frame_ms, 0.95)},
        {"track_ms_median", percentile(track_ms, 0.5)},
        {"keyframe_frame_ms_median", percentile(keyframe_frame_ms, 0.5)},
        {"keyframe_frame_ms_p95", percentile(keyframe_frame_ms, 0.95)},
        {"other_frame_ms_median", percentile(other_frame_ms, 0.5)},
        {"other_frame_ms_p95", percentile(other_frame_ms, 0.95)},
        {"map_wait_ms_median", percentile(wait_ms, 0.5)},
        {"map_wait_ms_p95", percentile(wait_ms, 0.95)},
        {"local_ba_ms_median", percentile(ba_ms, 0.5)},
        {"local_ba_ms_p95", percentile(ba_ms, 0.95)},
        {"local_bas", lm.bundle_adjustments},
        {"local_bas_interrupted", lm.bundle_adjustments_aborted},
        {"local_ba_free_keyframes_median", percentile(ba_free, 0.5)},
        {"local_ba_fixed_keyframes_median", percentile(ba_fixed, 0.5)},
        {"local_ba_landmarks_median", percentile(ba_landmarks, 0.5)},
        {"local_ba_observations_median", percentile(ba_observations, 0.5)},
        {"local_mapping_cpu_s",
         {{"refresh", steps.refresh},
          {"cull_landmarks", steps.cull_landmarks},
          {"triangulate", steps.triangulate},
          {"fuse", steps.fuse},
          {"bundle_adjustment", steps.bundle_adjustment},
          {"cull_keyframes", steps.cull_keyframes}}},
        {"loops", loops.size()},
        {"false_loops", false_loops},
        {"loops_rejected_drift", lc.loops_rejected_drift},
        {"loop_correction_ms_median", percentile(correction_ms, 0.5)},
        {"loop_essential_graph_ms_median", percentile(graph_ms, 0.5)},
        {"loop_locked_ms_median", percentile(locked_ms, 0.5)},
        {"global_ba_ms_last", lc.last_global_ba_ms},
        {"cpu_cores", cpu_s / wall_s},
        {"ate_before_loop_m", ate_before.rmse},
        {"ate_frames_m", ate_online.rmse},
        {"ate_keyframes_m", ate_keyframes.rmse},
        {"keyframes_sim3_scale", ate_keyframes.sim3_scale},
        {"ate_keyframes_sim3_m", ate_keyframes.sim3_rmse}};
    std::ofstream(out_dir + "/slam_" + scene + ".json") << json.dump(2) << "\n";
    std::ofstream(out_dir + "/slam_" + scene + "_frames.csv") << frame_rows.str();
    // The final keyframes and the truth at their times, for evaluation tools (TUM format).
    for (const auto& [name, poses] : {std::pair{"keyframes", &keyframes_final},
                                      std::pair{"keyframes_truth", &keyframes_truth}}) {
      if (!writeTumTrajectory(out_dir + "/slam_" + scene + "_" + name + ".tum", *poses, &error))
        std::fprintf(stderr, "%s\n", error.c_str());
    }
    TrajectoryPlotConfig plot;
    char title[160];
    std::snprintf(title, sizeof(title), "%s: keyframe ATE %.3f m (%.2f %% of %.0f m), %zu loops",
                  scene.c_str(), ate_keyframes.rmse, 100.0 * ate_keyframes.rmse / path, path,
                  loops.size());
    plot.title = title;
    plot.estimate_label = "keyframes (final)";
    // The plot is a top view of a z-up world: turn --up into +z.
    const Eigen::Matrix3d turn = upTurn(*up);
    const auto turned = [&turn](StampedTrajectory poses) {
      for (StampedPose& pose : poses) {
        pose.T_G_C = Transformationd(turn * pose.T_G_C.rotation().toRotationMatrix(),
                                      turn * pose.T_G_C.translation());
      }
      return poses;
    };
    if (!writeTrajectoryPlotPng(out_dir + "/slam_" + scene + "_trajectory.png", turned(truth),
                                turned(keyframes_final), plot, &error)) {
      std::fprintf(stderr, "plot: %s\n", error.c_str());
    }
  }
  return 0;
}

}  // namespace
}  // namespace cblox

int main(int argc, char** argv) { return cblox::run(argc, argv); }
