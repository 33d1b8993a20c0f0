#include "daemon/tracker/tracker_config.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <initializer_list>
#include <limits>
#include <variant>

#include "daemon/common/input_silence.h"
#include "daemon/common/yaml_config.h"
#include "daemon/tracker/calibration_file.h"

namespace cblox {
namespace {

void throwIfInvalid(const std::string& path, const std::string& error) {
  if (!error.empty()) throw ConfigError(path + ": " + error);
}

// An integer setting read as int64 and checked against [min, max] (sizes and seeds whose
// YAML conversion to unsigned types would not reject negative numbers).
template <typename T>
void readInteger(const YAML::Node& node, const std::string& path, const char* key, int64_t min,
                 int64_t max, T* value) {
  int64_t v = static_cast<int64_t>(*value);
  readOptional(node, path, key, &v);
  if (v < min || v > max) {
    throw ConfigError(path + "." + key + ": must be in [" + std::to_string(min) + ", " +
                      std::to_string(max) + "], got " + std::to_string(v));
  }
  *value = static_cast<T>(v);
}

using FieldTarget = std::variant<int*, double*, float*, bool*, std::string*>;
struct Field {
  const char* key;
  FieldTarget target;
};

// Reads the `fields` present in `node` (a map of settings) and rejects any key that is
// neither a field nor one of `other_keys` (which the caller reads). False when `node` is
// absent (everything keeps its value).
bool readSection(const YAML::Node& node, const std::string& path,
                 std::initializer_list<Field> fields,
                 std::initializer_list<const char*> other_keys = {}) {
  if (isAbsent(node)) return false;
  if (!node.IsMap()) throw ConfigError(path + ": expected a map of settings");
  for (const auto& entry : node) {
    const std::string key = entry.first.as<std::string>();
    const bool known =
        std::any_of(fields.begin(), fields.end(), [&](const Field& f) { return key == f.key; }) ||
        std::any_of(other_keys.begin(), other_keys.end(), [&](const char* k) { return key == k; });
    if (!known) throw ConfigError(path + "." + key + ": unknown setting");
  }
  for (const Field& field : fields) {
    std::visit([&](auto* target) { readOptional(node, path, field.key, target); }, field.target);
  }
  return true;
}

void loadBundleAdjustment(const YAML::Node& node, const std::string& path,
                          BundleAdjustmentConfig* ba) {
  if (readSection(node, path,
                  {{"first_pass_iterations", &ba->first_pass_iterations},
                   {"second_pass_iterations", &ba->second_pass_iterations},
                   {"num_threads", &ba->solver.num_threads},
                   {"max_time_s", &ba->solver.max_time_s},
                   {"dense_schur_max_free_keyframes", &ba->dense_schur_max_free_keyframes},
                   {"native_max_free_keyframes", &ba->native_max_free_keyframes},
                   {"native_sparse", &ba->native_sparse}})) {
    throwIfInvalid(path, validate(*ba));
  }
}

void loadFrames(const YAML::Node& node, FrameBuilderConfig* frames) {
  if (!readSection(node, "frames",
                   {{"parallel_stereo_extraction", &frames->parallel_stereo_extraction},
                    {"grid_cols", &frames->grid_cols},
                    {"grid_rows", &frames->grid_rows}},
                   {"orb", "stereo"})) {
    return;
  }
  OrbExtractorConfig& orb = frames->orb;
  if (readSection(node["orb"], "frames.orb",
                  {{"num_features", &orb.num_features},
                   {"scale_factor", &orb.scale_factor},
                   {"num_levels", &orb.num_levels},
                   {"initial_fast_threshold", &orb.initial_fast_threshold},
                   {"min_fast_threshold", &orb.min_fast_threshold}})) {
    throwIfInvalid("frames.orb", orb.validate());
  }
  StereoMatcherConfig& s = frames->stereo;
  if (readSection(node["stereo"], "frames.stereo",
                  {{"max_descriptor_distance", &s.max_descriptor_distance},
                   {"max_octave_difference", &s.max_octave_difference},
                   {"row_tolerance_factor", &s.row_tolerance_factor},
                   {"min_depth_m", &s.min_depth_m},
                   {"sad_half_window", &s.sad_half_window},
                   {"sad_search_half_range", &s.sad_search_half_range},
                   {"sad_outlier_factor", &s.sad_outlier_factor}})) {
    throwIfInvalid("frames.stereo", s.validate());
  }
  throwIfInvalid("frames", frames->validate());
}

void loadTracking(const YAML::Node& node, TrackerConfig* t) {
  if (readSection(node, "tracker",
                  {{"min_features_to_initialize", &t->min_features_to_initialize},
                   {"min_new_landmarks_per_keyframe", &t->min_new_landmarks_per_keyframe},
                   {"max_frames_between_keyframes", &t->max_frames_between_keyframes},
                   {"min_frames_between_keyframes", &t->min_frames_between_keyframes},
                   {"reference_ratio", &t->reference_ratio},
                   {"tracked_close_min", &t->tracked_close_min},
                   {"untracked_close_min", &t->untracked_close_min},
                   {"close_points_min_frames", &t->close_points_min_frames},
                   {"close_points_turn_deg", &t->close_points_turn_deg},
                   {"close_points_gap_min_inliers", &t->close_points_gap_min_inliers},
                   {"last_frame_search_radius", &t->last_frame_search_radius},
                   {"local_map_search_radius", &t->local_map_search_radius},
                   {"relocalized_search_radius", &t->relocalized_search_radius},
                   {"min_motion_model_matches", &t->min_motion_model_matches},
                   {"min_reference_matches", &t->min_reference_matches},
                   {"min_pose_inliers", &t->min_pose_inliers},
                   {"min_local_map_inliers", &t->min_local_map_inliers},
                   {"min_local_map_inliers_after_relocalization",
                    &t->min_local_map_inliers_after_relocalization},
                   {"max_local_keyframes", &t->max_local_keyframes},
                   {"max_relocalization_candidates", &t->max_relocalization_candidates},
                   {"min_relocalization_matches", &t->min_relocalization_matches},
                   {"pnp_iterations", &t->pnp_iterations},
                   {"pnp_reprojection_error_px", &t->pnp_reprojection_error_px}})) {
    throwIfInvalid("tracker", t->validate());
  }
}

void loadLocalMapping(const YAML::Node& node, LocalMapperConfig* m) {
  const std::string path = "local_mapping";
  if (!readSection(node, path,
                   {{"min_found_ratio", &m->min_found_ratio},
                    {"min_observations", &m->min_observations},
                    {"fuse_neighbours", &m->fuse_neighbours},
                    {"fuse_second_neighbours", &m->fuse_second_neighbours},
                    {"fuse_radius", &m->fuse_radius},
                    {"cull_keyframes", &m->cull_keyframes},
                    {"redundant_ratio", &m->redundant_ratio},
                    {"create_new_landmarks", &m->create_new_landmarks},
                    {"triangulation_neighbours", &m->triangulation.neighbours},
                    {"local_ba_max_keyframes", &m->local_ba_max_keyframes}},
                   {"bundle_adjustment", "niceness", "disparity_correction"})) {
    return;
  }
  loadBundleAdjustment(node["bundle_adjustment"], path + ".bundle_adjustment",
                       &m->bundle_adjustment);
  DisparityCorrectionConfig& d = m->disparity_correction;
  readSection(node["disparity_correction"], path + ".disparity_correction",
              {{"enabled", &d.enabled},
               {"every_keyframes", &d.every_keyframes},
               {"settled_every_keyframes", &d.settled_every_keyframes},
               {"window", &d.window},
               {"min_estimates", &d.min_estimates},
               {"max_spread_px", &d.max_spread_px},
               {"settled_tolerance_px", &d.settled_tolerance_px},
               {"min_correction_px", &d.min_correction_px},
               {"max_abs_px", &d.max_abs_px},
               {"max_landmarks", &d.solver.max_landmarks},
               {"min_stereo_observations", &d.solver.min_stereo_observations},
               {"iterations", &d.solver.iterations}});
  throwIfInvalid(path, m->validate());
}

void loadLoopClosing(const YAML::Node& node, SlamSystemConfig* slam) {
  const std::string path = "loop_closing";
  LoopCloserConfig& l = slam->loop_closing;
  if (!readSection(node, path,
                   {{"enabled", &slam->loop_closing_enabled},
                    {"min_keyframes_between_loops", &l.min_keyframes_between_loops},
                    {"consistency_threshold", &l.consistency_threshold},
                    {"min_bow_matches", &l.min_bow_matches},
                    {"ransac_iterations", &l.ransac_iterations},
                    {"min_ransac_inliers", &l.min_ransac_inliers},
                    {"min_projection_matches", &l.min_projection_matches},
                    {"max_drift_m", &l.max_drift_m},
                    {"max_drift_ratio", &l.max_drift_ratio},
                    {"essential_graph_min_weight", &l.essential_graph_min_weight},
                    {"global_bundle_adjustment", &l.global_bundle_adjustment}},
                   {"seed", "pose_graph", "global_ba", "niceness"})) {
    return;
  }
  readInteger(node, path, "seed", 0, std::numeric_limits<uint32_t>::max(), &l.seed);
  if (readSection(node["pose_graph"], path + ".pose_graph",
                  {{"max_iterations", &l.pose_graph.max_iterations},
                   {"num_threads", &l.pose_graph.solver.num_threads},
                   {"max_time_s", &l.pose_graph.solver.max_time_s}})) {
    throwIfInvalid(path + ".pose_graph", validate(l.pose_graph));
  }
  loadBundleAdjustment(node["global_ba"], path + ".global_ba", &l.global_ba);
  throwIfInvalid(path, l.validate());
}

}  // namespace

TrackerMode parseTrackerMode(const std::string& name) {
  if (name == "stereo") return TrackerMode::kStereo;
  if (name == "rgbd") return TrackerMode::kRgbd;
  throw ConfigError("mode must be stereo or rgbd, got '" + name + "'");
}

InitialPose parseInitialPose(const std::string& name) {
  if (name == "identity") return InitialPose::kIdentity;
  if (name == "ground_truth") return InitialPose::kGroundTruth;
  throw ConfigError("initial_pose must be identity or ground_truth, got '" + name + "'");
}

std::string TrackerProcessConfig::validate() const {
  if (std::string e = tracker.validate(); !e.empty()) return e;
  for (const std::string* channel :
       {&stereo_channel, &depth_channel, &ground_truth_channel, &frame_pose_channel,
        &keyframe_channel, &keyframe_poses_channel, &heartbeat_channel, &covariance_request_channel,
        &covariance_reply_channel}) {
    if (channel->empty()) return "channels: a channel name is empty";
  }
  if (calibration_source == CalibrationSource::kFile && calibration_file.empty()) {
    return "camera.calibration_file must name a file when camera.calibration is file";
  }
  if (!(status_period_s > 0.0) || !std::isfinite(status_period_s)) {
    return "status.period_s must be finite and > 0";
  }
  if (!(progress_period_s > 0.0) || !std::isfinite(progress_period_s)) {
    return "status.progress_period_s must be finite and > 0";
  }
  if (std::string e = validateInputSilence(input_silence_s); !e.empty()) return e;
  return {};
}

void finishTrackerConfig(TrackerProcessConfig* config) {
  config->tracker.calibration.reset();
  if (config->calibration_source == CalibrationSource::kFile && !config->calibration_file.empty()) {
    try {
      config->tracker.calibration = loadCalibrationFile(
          config->calibration_file, config->tracker.mode == TrackerMode::kStereo);
    } catch (const ConfigError& e) {
      throw ConfigError(std::string("camera.calibration_file: ") + e.what());
    }
  }
  throwIfInvalid("tracker", config->validate());
}

TrackerProcessConfig loadTrackerConfig(const YAML::Node& root) {
  TrackerProcessConfig config;
  TrackerNodeConfig& t = config.tracker;
  const std::string top = "tracker";
  if (!readSection(
          root, top,
          {{"lcm_url", &config.lcm_url},
           {"vocabulary", &config.vocabulary},
           {"input_silence_s", &config.input_silence_s}},
          {"mode", "initial_pose", "channels", "camera", "frames", "tracker", "local_mapping",
           "loop_closing", "covariance", "input", "image_check", "status", "checkpoint"})) {
    finishTrackerConfig(&config);
    return config;
  }
  readOptionalEnum(root, top, "mode",
                   {{"stereo", TrackerMode::kStereo}, {"rgbd", TrackerMode::kRgbd}}, &t.mode);
  readOptionalEnum(
      root, top, "initial_pose",
      {{"identity", InitialPose::kIdentity}, {"ground_truth", InitialPose::kGroundTruth}},
      &t.initial_pose);
  readSection(root["channels"], "channels",
              {{"stereo", &config.stereo_channel},
               {"depth", &config.depth_channel},
               {"ground_truth_pose", &config.ground_truth_channel},
               {"frame_pose", &config.frame_pose_channel},
               {"keyframe", &config.keyframe_channel},
               {"keyframe_poses", &config.keyframe_poses_channel},
               {"heartbeat", &config.heartbeat_channel},
               {"covariance_request", &config.covariance_request_channel},
               {"covariance_reply", &config.covariance_reply_channel}});
  const YAML::Node camera = root["camera"];
  if (readSection(camera, "camera",
                  {{"calibration_file", &config.calibration_file},
                   {"close_depth_baselines", &t.close_depth_baselines},
                   {"rgbd_baseline_m", &t.rgbd_baseline_m}},
                  {"calibration"})) {
    readOptionalEnum(camera, "camera", "calibration",
                     {{"message", CalibrationSource::kMessage}, {"file", CalibrationSource::kFile}},
                     &config.calibration_source);
  }

  loadFrames(root["frames"], &t.slam.frames);
  loadTracking(root["tracker"], &t.slam.tracker);
  loadLocalMapping(root["local_mapping"], &t.slam.local_mapping);
  loadLoopClosing(root["loop_closing"], &t.slam);
  if (const YAML::Node n = root["local_mapping"]; n.IsDefined() && n.IsMap()) {
    readInteger(n, "local_mapping", "niceness", 0, 19, &t.local_mapping_niceness);
  }
  if (const YAML::Node n = root["loop_closing"]; n.IsDefined() && n.IsMap()) {
    readInteger(n, "loop_closing", "niceness", 0, 19, &t.loop_closing_niceness);
  }
  const YAML::Node covariance = root["covariance"];
  if (readSection(covariance, "covariance",
                  {{"max_linearization_age_s", &t.covariance.max_linearization_age_s},
                   {"min_linearization_interval_s", &t.covariance.min_linearization_interval_s}},
                  {"method", "max_queued_requests", "niceness"})) {
    readOptionalEnum(covariance, "covariance", "method",
                     {{"constrained_ordering", CovarianceMethod::kConstrainedOrdering},
                      {"batch", CovarianceMethod::kBatch},
                      {"kaess_recovery", CovarianceMethod::kKaessRecovery},
                      {"sparse_solve", CovarianceMethod::kSparseSolve}},
                     &t.covariance.method);
    readInteger(covariance, "covariance", "max_queued_requests", 1, 1024,
                &t.covariance.max_queued_requests);
    readInteger(covariance, "covariance", "niceness", 0, 19, &t.covariance.niceness);
  }

  readSection(root["checkpoint"], "checkpoint",
              {{"dir", &t.checkpoint.dir},
               {"period_s", &t.checkpoint.period_s},
               {"resume", &t.checkpoint.resume}});

  const YAML::Node input = root["input"];
  if (readSection(input, "input",
                  {{"ground_truth_wait_s", &t.ground_truth_wait_s},
                   {"restart_after_backwards_s", &t.restart_after_backwards_s},
                   {"catch_up", &t.catch_up}},
                  {"queue_capacity"})) {
    readInteger(input, "input", "queue_capacity", 1, 16, &t.queue_capacity);
  }
  ImageCheckConfig& check = t.image_check;
  if (readSection(root["image_check"], "image_check",
                  {{"enabled", &check.enabled},
                   {"dark_level", &check.dark_level},
                   {"bright_level", &check.bright_level},
                   {"max_fraction", &check.max_fraction},
                   {"min_mean_gradient", &check.min_mean_gradient}})) {
    throwIfInvalid("image_check", check.validate());
  }
  const YAML::Node status = root["status"];
  if (readSection(status, "status",
                  {{"period_s", &config.status_period_s},
                   {"progress_period_s", &config.progress_period_s},
                   {"log_interval_s", &t.log_interval_s}},
                  {"timing_window"})) {
    readInteger(status, "status", "timing_window", 1, 1000000, &t.timing_window);
  }

  finishTrackerConfig(&config);
  return config;
}

std::optional<TrackerNodeConfig> loadTrackerNodeSettings(const std::string& path,
                                                         std::string* error) {
  if (path.empty()) return TrackerNodeConfig{};
  try {
    return loadTrackerConfig(YAML::LoadFile(path)).tracker;
  } catch (const std::exception& e) {
    if (error != nullptr) *error = path + ": " + e.what();
    return std::nullopt;
  }
}

std::optional<SlamSystemConfig> loadSlamSettings(const std::string& path, std::string* error) {
  std::optional<TrackerNodeConfig> node = loadTrackerNodeSettings(path, error);
  if (!node) return std::nullopt;
  return node->slam;
}

}  // namespace cblox
