#include "daemon/tracker/tracker_config.h"

#include <cstdio>
#include <fstream>
#include <optional>
#include <regex>
#include <string>

#include <gtest/gtest.h>

#include "daemon/common/yaml_config.h"
#include "daemon/tracker/calibration_file.h"
#include "test/test_support/temp_dir.h"

namespace cblox {
namespace {

void expectSameBundleAdjustment(const BundleAdjustmentConfig& a, const BundleAdjustmentConfig& b) {
  EXPECT_EQ(a.first_pass_iterations, b.first_pass_iterations);
  EXPECT_EQ(a.second_pass_iterations, b.second_pass_iterations);
  EXPECT_EQ(a.solver.num_threads, b.solver.num_threads);
  EXPECT_EQ(a.solver.max_time_s, b.solver.max_time_s);
  EXPECT_EQ(a.dense_schur_max_free_keyframes, b.dense_schur_max_free_keyframes);
  EXPECT_EQ(a.native_max_free_keyframes, b.native_max_free_keyframes);
  EXPECT_EQ(a.native_sparse, b.native_sparse);
}

TEST(TrackerConfigTest, ShippedYamlMatchesTheCodeDefaults) {
  const TrackerProcessConfig shipped =
      loadTrackerConfig(loadYamlFile(std::string(CBLOX_CONFIG_DIR) + "/tracker.yaml"));
  const TrackerProcessConfig defaults;
  EXPECT_TRUE(defaults.validate().empty()) << defaults.validate();
  const TrackerNodeConfig& a = shipped.tracker;
  const TrackerNodeConfig& b = defaults.tracker;
  EXPECT_EQ(a.mode, b.mode);
  EXPECT_EQ(shipped.lcm_url, defaults.lcm_url);
  EXPECT_EQ(shipped.vocabulary, defaults.vocabulary);
  EXPECT_EQ(a.initial_pose, b.initial_pose);
  EXPECT_EQ(shipped.stereo_channel, defaults.stereo_channel);
  EXPECT_EQ(shipped.depth_channel, defaults.depth_channel);
  EXPECT_EQ(shipped.ground_truth_channel, defaults.ground_truth_channel);
  EXPECT_EQ(shipped.frame_pose_channel, defaults.frame_pose_channel);
  EXPECT_EQ(shipped.keyframe_channel, defaults.keyframe_channel);
  EXPECT_EQ(shipped.keyframe_poses_channel, defaults.keyframe_poses_channel);
  EXPECT_EQ(shipped.heartbeat_channel, defaults.heartbeat_channel);
  EXPECT_EQ(shipped.covariance_request_channel, defaults.covariance_request_channel);
  EXPECT_EQ(shipped.covariance_reply_channel, defaults.covariance_reply_channel);
  EXPECT_EQ(a.covariance.method, b.covariance.method);
  EXPECT_EQ(a.covariance.max_queued_requests, b.covariance.max_queued_requests);
  EXPECT_EQ(a.covariance.niceness, b.covariance.niceness);
  EXPECT_EQ(a.covariance.max_linearization_age_s, b.covariance.max_linearization_age_s);
  EXPECT_EQ(a.covariance.min_linearization_interval_s, b.covariance.min_linearization_interval_s);
  EXPECT_EQ(a.checkpoint.dir, b.checkpoint.dir);
  EXPECT_EQ(a.checkpoint.period_s, b.checkpoint.period_s);
  EXPECT_EQ(a.checkpoint.resume, b.checkpoint.resume);
  EXPECT_EQ(shipped.calibration_source, defaults.calibration_source);
  EXPECT_EQ(shipped.calibration_file, defaults.calibration_file);
  EXPECT_FALSE(a.calibration.has_value());
  EXPECT_EQ(a.close_depth_baselines, b.close_depth_baselines);
  EXPECT_EQ(a.rgbd_baseline_m, b.rgbd_baseline_m);
  const OrbExtractorConfig &orb = a.slam.frames.orb, &orb0 = b.slam.frames.orb;
  EXPECT_EQ(orb.num_features, orb0.num_features);
  EXPECT_EQ(orb.scale_factor, orb0.scale_factor);
  EXPECT_EQ(orb.num_levels, orb0.num_levels);
  EXPECT_EQ(orb.initial_fast_threshold, orb0.initial_fast_threshold);
  EXPECT_EQ(orb.min_fast_threshold, orb0.min_fast_threshold);
  EXPECT_EQ(a.slam.tracker.min_features_to_initialize, b.slam.tracker.min_features_to_initialize);
  EXPECT_EQ(a.slam.tracker.max_frames_between_keyframes,
            b.slam.tracker.max_frames_between_keyframes);
  EXPECT_EQ(a.slam.local_mapping.cull_keyframes, b.slam.local_mapping.cull_keyframes);
  EXPECT_EQ(a.slam.loop_closing_enabled, b.slam.loop_closing_enabled);
  EXPECT_EQ(a.slam.loop_closing.global_bundle_adjustment,
            b.slam.loop_closing.global_bundle_adjustment);
  EXPECT_EQ(a.queue_capacity, b.queue_capacity);
  EXPECT_EQ(a.catch_up, b.catch_up);
  EXPECT_EQ(a.ground_truth_wait_s, b.ground_truth_wait_s);
  EXPECT_EQ(a.image_check.enabled, b.image_check.enabled);
  EXPECT_EQ(a.image_check.dark_level, b.image_check.dark_level);
  EXPECT_EQ(a.image_check.bright_level, b.image_check.bright_level);
  EXPECT_EQ(a.image_check.max_fraction, b.image_check.max_fraction);
  EXPECT_EQ(a.image_check.min_mean_gradient, b.image_check.min_mean_gradient);
  EXPECT_EQ(shipped.status_period_s, defaults.status_period_s);
  EXPECT_EQ(shipped.progress_period_s, defaults.progress_period_s);
  EXPECT_EQ(a.timing_window, b.timing_window);
  EXPECT_EQ(a.log_interval_s, b.log_interval_s);
}

// The commented-out keys of the shipped file, uncommented, are the code's defaults too.
TEST(TrackerConfigTest, CommentedKeysOfTheShippedYamlAreTheDefaults) {
  std::ifstream in(std::string(CBLOX_CONFIG_DIR) + "/tracker.yaml");
  ASSERT_TRUE(in.good());
  // "  # key: value" lines (indented 2-8 spaces: settings, not the comments in the right
  // column) lose their "# ".
  const std::regex commented_key("^( {2,8})# ( *[a-z_]+:.*)$");
  std::string text, line;
  while (std::getline(in, line)) text += std::regex_replace(line, commented_key, "$1$2") + "\n";
  const TrackerProcessConfig all = loadTrackerConfig(YAML::Load(text));
  const SlamSystemConfig& a = all.tracker.slam;
  const SlamSystemConfig b;
  const StereoMatcherConfig &s = a.frames.stereo, &s0 = b.frames.stereo;
  EXPECT_EQ(s.max_descriptor_distance, s0.max_descriptor_distance);
  EXPECT_EQ(s.max_octave_difference, s0.max_octave_difference);
  EXPECT_EQ(s.row_tolerance_factor, s0.row_tolerance_factor);
  EXPECT_EQ(s.min_depth_m, s0.min_depth_m);
  EXPECT_EQ(s.sad_half_window, s0.sad_half_window);
  EXPECT_EQ(s.sad_search_half_range, s0.sad_search_half_range);
  EXPECT_EQ(s.sad_outlier_factor, s0.sad_outlier_factor);
  EXPECT_EQ(a.frames.parallel_stereo_extraction, b.frames.parallel_stereo_extraction);
  EXPECT_EQ(a.frames.grid_cols, b.frames.grid_cols);
  EXPECT_EQ(a.frames.grid_rows, b.frames.grid_rows);
  const TrackerConfig &t = a.tracker, &t0 = b.tracker;
  EXPECT_EQ(t.min_frames_between_keyframes, t0.min_frames_between_keyframes);
  EXPECT_EQ(t.min_new_landmarks_per_keyframe, t0.min_new_landmarks_per_keyframe);
  EXPECT_EQ(t.reference_ratio, t0.reference_ratio);
  EXPECT_EQ(t.tracked_close_min, t0.tracked_close_min);
  EXPECT_EQ(t.untracked_close_min, t0.untracked_close_min);
  EXPECT_EQ(t.close_points_min_frames, t0.close_points_min_frames);
  EXPECT_EQ(t.close_points_turn_deg, t0.close_points_turn_deg);
  EXPECT_EQ(t.close_points_gap_min_inliers, t0.close_points_gap_min_inliers);
  EXPECT_EQ(t.last_frame_search_radius, t0.last_frame_search_radius);
  EXPECT_EQ(t.local_map_search_radius, t0.local_map_search_radius);
  EXPECT_EQ(t.relocalized_search_radius, t0.relocalized_search_radius);
  EXPECT_EQ(t.min_motion_model_matches, t0.min_motion_model_matches);
  EXPECT_EQ(t.min_reference_matches, t0.min_reference_matches);
  EXPECT_EQ(t.min_pose_inliers, t0.min_pose_inliers);
  EXPECT_EQ(t.min_local_map_inliers, t0.min_local_map_inliers);
  EXPECT_EQ(t.min_local_map_inliers_after_relocalization,
            t0.min_local_map_inliers_after_relocalization);
  EXPECT_EQ(t.max_local_keyframes, t0.max_local_keyframes);
  EXPECT_EQ(t.max_relocalization_candidates, t0.max_relocalization_candidates);
  EXPECT_EQ(t.min_relocalization_matches, t0.min_relocalization_matches);
  EXPECT_EQ(t.pnp_iterations, t0.pnp_iterations);
  EXPECT_EQ(t.pnp_reprojection_error_px, t0.pnp_reprojection_error_px);
  const LocalMapperConfig &m = a.local_mapping, &m0 = b.local_mapping;
  EXPECT_EQ(m.min_found_ratio, m0.min_found_ratio);
  EXPECT_EQ(m.min_observations, m0.min_observations);
  EXPECT_EQ(m.fuse_neighbours, m0.fuse_neighbours);
  EXPECT_EQ(m.fuse_second_neighbours, m0.fuse_second_neighbours);
  EXPECT_EQ(m.fuse_radius, m0.fuse_radius);
  EXPECT_EQ(m.redundant_ratio, m0.redundant_ratio);
  EXPECT_EQ(m.local_ba_max_keyframes, m0.local_ba_max_keyframes);
  const DisparityCorrectionConfig &d = m.disparity_correction, &d0 = m0.disparity_correction;
  EXPECT_EQ(d.enabled, d0.enabled);
  EXPECT_EQ(d.every_keyframes, d0.every_keyframes);
  EXPECT_EQ(d.settled_every_keyframes, d0.settled_every_keyframes);
  EXPECT_EQ(d.window, d0.window);
  EXPECT_EQ(d.min_estimates, d0.min_estimates);
  EXPECT_EQ(d.max_spread_px, d0.max_spread_px);
  EXPECT_EQ(d.settled_tolerance_px, d0.settled_tolerance_px);
  EXPECT_EQ(d.min_correction_px, d0.min_correction_px);
  EXPECT_EQ(d.max_abs_px, d0.max_abs_px);
  EXPECT_EQ(d.solver.max_landmarks, d0.solver.max_landmarks);
  EXPECT_EQ(d.solver.min_stereo_observations, d0.solver.min_stereo_observations);
  EXPECT_EQ(d.solver.iterations, d0.solver.iterations);
  expectSameBundleAdjustment(m.bundle_adjustment, m0.bundle_adjustment);
  const LoopCloserConfig &l = a.loop_closing, &l0 = b.loop_closing;
  EXPECT_EQ(l.min_keyframes_between_loops, l0.min_keyframes_between_loops);
  EXPECT_EQ(l.consistency_threshold, l0.consistency_threshold);
  EXPECT_EQ(l.min_bow_matches, l0.min_bow_matches);
  EXPECT_EQ(l.ransac_iterations, l0.ransac_iterations);
  EXPECT_EQ(l.min_ransac_inliers, l0.min_ransac_inliers);
  EXPECT_EQ(l.min_projection_matches, l0.min_projection_matches);
  EXPECT_EQ(l.essential_graph_min_weight, l0.essential_graph_min_weight);
  EXPECT_EQ(l.seed, l0.seed);
  EXPECT_EQ(l.pose_graph.max_iterations, l0.pose_graph.max_iterations);
  EXPECT_EQ(l.pose_graph.solver.num_threads, l0.pose_graph.solver.num_threads);
  EXPECT_EQ(l.pose_graph.solver.max_time_s, l0.pose_graph.solver.max_time_s);
  expectSameBundleAdjustment(l.global_ba, l0.global_ba);
}

TEST(TrackerConfigTest, ReadsOverrides) {
  const TrackerProcessConfig config = loadTrackerConfig(YAML::Load(
      "mode: rgbd\nlcm_url: udpm://x\nvocabulary: none\ninitial_pose: ground_truth\n"
      "channels: {stereo: S, depth: D, ground_truth_pose: G, frame_pose: F, keyframe: K,\n"
      "           keyframe_poses: P, heartbeat: H, covariance_request: CQ,\n"
      "           covariance_reply: CR}\n"
      "covariance: {method: kaess_recovery, max_queued_requests: 2, niceness: 0,\n"
      "             max_linearization_age_s: 1.5, min_linearization_interval_s: 2.5}\n"
      "camera: {close_depth_baselines: 35, rgbd_baseline_m: 0.07}\n"
      "frames: {orb: {num_features: 1500, num_levels: 6}, stereo: {min_depth_m: 0.5},\n"
      "         parallel_stereo_extraction: false}\n"
      "tracker: {min_features_to_initialize: 300, max_frames_between_keyframes: 10,\n"
      "          pnp_reprojection_error_px: 3.0, close_points_gap_min_inliers: 90}\n"
      "local_mapping: {cull_keyframes: true, local_ba_max_keyframes: 7,\n"
      "                bundle_adjustment: {num_threads: 2, max_time_s: 0.2},\n"
      "                disparity_correction: {enabled: false, window: 5, min_estimates: 3,\n"
      "                                       max_landmarks: 300}}\n"
      "loop_closing: {enabled: false, seed: 7, pose_graph: {max_iterations: 30},\n"
      "               global_ba: {first_pass_iterations: 4}}\n"
      "input: {queue_capacity: 2, ground_truth_wait_s: 0.5, catch_up: false}\n"
      "image_check: {enabled: false, dark_level: 5, bright_level: 250, max_fraction: 0.9,\n"
      "              min_mean_gradient: 0.5}\n"
      "status: {period_s: 0.5, progress_period_s: 2, timing_window: 10, log_interval_s: 1}\n"
      "checkpoint: {dir: /var/lib/cblox/tracker, period_s: 30, resume: false}\n"));
  const TrackerNodeConfig& t = config.tracker;
  EXPECT_EQ(t.mode, TrackerMode::kRgbd);
  EXPECT_EQ(config.lcm_url, "udpm://x");
  EXPECT_EQ(config.vocabulary, "none");
  EXPECT_EQ(t.initial_pose, InitialPose::kGroundTruth);
  EXPECT_EQ(config.stereo_channel, "S");
  EXPECT_EQ(config.depth_channel, "D");
  EXPECT_EQ(config.ground_truth_channel, "G");
  EXPECT_EQ(config.frame_pose_channel, "F");
  EXPECT_EQ(config.keyframe_channel, "K");
  EXPECT_EQ(config.keyframe_poses_channel, "P");
  EXPECT_EQ(config.heartbeat_channel, "H");
  EXPECT_EQ(config.covariance_request_channel, "CQ");
  EXPECT_EQ(config.covariance_reply_channel, "CR");
  EXPECT_EQ(t.covariance.method, CovarianceMethod::kKaessRecovery);
  EXPECT_EQ(t.covariance.max_queued_requests, 2u);
  EXPECT_EQ(t.covariance.niceness, 0);
  EXPECT_EQ(t.covariance.max_linearization_age_s, 1.5);
  EXPECT_EQ(t.covariance.min_linearization_interval_s, 2.5);
  EXPECT_EQ(t.checkpoint.dir, "/var/lib/cblox/tracker");
  EXPECT_EQ(t.checkpoint.period_s, 30.0);
  EXPECT_FALSE(t.checkpoint.resume);
  EXPECT_EQ(t.close_depth_baselines, 35.0);
  EXPECT_EQ(t.rgbd_baseline_m, 0.07);
  EXPECT_EQ(t.slam.tracker.close_points_gap_min_inliers, 90);
  EXPECT_EQ(t.slam.frames.orb.num_features, 1500);
  EXPECT_EQ(t.slam.frames.orb.num_levels, 6);
  EXPECT_EQ(t.slam.frames.stereo.min_depth_m, 0.5);
  EXPECT_FALSE(t.slam.frames.parallel_stereo_extraction);
  EXPECT_EQ(t.slam.tracker.min_features_to_initialize, 300);
  EXPECT_EQ(t.slam.tracker.max_frames_between_keyframes, 10);
  EXPECT_EQ(t.slam.tracker.pnp_reprojection_error_px, 3.0);
  EXPECT_TRUE(t.slam.local_mapping.cull_keyframes);
  EXPECT_EQ(t.slam.local_mapping.local_ba_max_keyframes, 7);
  EXPECT_EQ(t.slam.local_mapping.bundle_adjustment.solver.num_threads, 2);
  EXPECT_EQ(t.slam.local_mapping.bundle_adjustment.solver.max_time_s, 0.2);
  EXPECT_FALSE(t.slam.local_mapping.disparity_correction.enabled);
  EXPECT_EQ(t.slam.local_mapping.disparity_correction.window, 5);
  EXPECT_EQ(t.slam.local_mapping.disparity_correction.min_estimates, 3);
  EXPECT_EQ(t.slam.local_mapping.disparity_correction.solver.max_landmarks, 300);
  EXPECT_FALSE(t.slam.loop_closing_enabled);
  EXPECT_EQ(t.slam.loop_closing.seed, 7u);
  EXPECT_EQ(t.slam.loop_closing.pose_graph.max_iterations, 30);
  EXPECT_EQ(t.slam.loop_closing.global_ba.first_pass_iterations, 4);
  EXPECT_EQ(t.slam.loop_closing.global_ba.second_pass_iterations, 0);  // the global preset
  EXPECT_EQ(t.queue_capacity, 2u);
  EXPECT_FALSE(t.catch_up);
  EXPECT_EQ(t.ground_truth_wait_s, 0.5);
  EXPECT_FALSE(t.image_check.enabled);
  EXPECT_EQ(t.image_check.dark_level, 5);
  EXPECT_EQ(t.image_check.bright_level, 250);
  EXPECT_EQ(t.image_check.max_fraction, 0.9);
  EXPECT_EQ(t.image_check.min_mean_gradient, 0.5);
  EXPECT_EQ(config.status_period_s, 0.5);
  EXPECT_EQ(config.progress_period_s, 2.0);
  EXPECT_EQ(t.timing_window, 10u);
  EXPECT_EQ(t.log_interval_s, 1.0);
}

// loadSlamSettings reads a file's SLAM settings as loadTrackerConfig does, and says what is
// wrong (the path, and the key) instead of throwing.
TEST(TrackerConfigTest, SlamSettingsOfAFile) {
  const test::TempDir dir("slam_settings");
  const std::string path = (dir.path() / "tracker.yaml").string();
  std::ofstream(path) << "tracker: {reference_ratio: 0.5, close_points_gap_min_inliers: 100}\n"
                         "loop_closing: {global_ba: {first_pass_iterations: 30}}\n";
  std::string error;
  const std::optional<SlamSystemConfig> slam = loadSlamSettings(path, &error);
  ASSERT_TRUE(slam.has_value()) << error;
  EXPECT_EQ(slam->tracker.reference_ratio, 0.5);
  EXPECT_EQ(slam->tracker.close_points_gap_min_inliers, 100);
  EXPECT_EQ(slam->loop_closing.global_ba.first_pass_iterations, 30);
  EXPECT_EQ(slam->tracker.max_frames_between_keyframes,
            TrackerConfig{}.max_frames_between_keyframes);  // absent: the default

  const std::string missing = (dir.path() / "absent.yaml").string();
  EXPECT_FALSE(loadSlamSettings(missing, &error).has_value());
  EXPECT_EQ(error.rfind(missing + ": ", 0), 0u) << error;
  std::ofstream(path) << "tracker: {close_points_gap_min_inliers: -1}\n";
  EXPECT_FALSE(loadSlamSettings(path, &error).has_value());
  EXPECT_NE(error.find("close_points_gap_min_inliers"), std::string::npos) << error;
  EXPECT_EQ(error.rfind(path + ": ", 0), 0u) << error;
  EXPECT_FALSE(loadSlamSettings(path, nullptr).has_value());
  // No file named: the defaults.
  const std::optional<SlamSystemConfig> defaults = loadSlamSettings("", &error);
  ASSERT_TRUE(defaults.has_value());
  EXPECT_EQ(defaults->tracker.reference_ratio, TrackerConfig{}.reference_ratio);
}

// The SLAM threads' niceness: local_mapping.niceness and loop_closing.niceness, 10 by default,
// within [0, 19].
TEST(TrackerConfigTest, SlamThreadsNiceness) {
  const test::TempDir dir("slam_niceness");
  const std::string path = (dir.path() / "tracker.yaml").string();
  std::string error;
  const std::optional<TrackerNodeConfig> defaults = loadTrackerNodeSettings("", &error);
  ASSERT_TRUE(defaults.has_value());
  EXPECT_EQ(defaults->local_mapping_niceness, 10);
  EXPECT_EQ(defaults->loop_closing_niceness, 10);
  std::ofstream(path) << "local_mapping: {niceness: 3, fuse_radius: 2.5}\n"
                         "loop_closing: {niceness: 0}\n";
  const std::optional<TrackerNodeConfig> node = loadTrackerNodeSettings(path, &error);
  ASSERT_TRUE(node.has_value()) << error;
  EXPECT_EQ(node->local_mapping_niceness, 3);
  EXPECT_EQ(node->loop_closing_niceness, 0);
  EXPECT_EQ(node->slam.local_mapping.fuse_radius, 2.5f);
  std::ofstream(path) << "loop_closing: {niceness: 20}\n";
  EXPECT_FALSE(loadTrackerNodeSettings(path, &error).has_value());
  EXPECT_NE(error.find("loop_closing.niceness"), std::string::npos) << error;
  std::ofstream(path) << "local_mapping: {niceness: -1}\n";
  EXPECT_FALSE(loadTrackerNodeSettings(path, &error).has_value());
  EXPECT_NE(error.find("local_mapping.niceness"), std::string::npos) << error;
}

// The README's street-drive example loads and sets exactly what it says.
TEST(TrackerConfigTest, StreetDriveExampleLoads) {
  std::string error;
  const std::optional<SlamSystemConfig> slam = loadSlamSettings(
      std::string(CBLOX_CONFIG_DIR) + "/examples/tracker_street_drive.yaml", &error);
  ASSERT_TRUE(slam.has_value()) << error;
  EXPECT_EQ(slam->tracker.reference_ratio, 0.5);
  EXPECT_EQ(slam->tracker.close_points_min_frames, 16);
  EXPECT_EQ(slam->tracker.close_points_turn_deg, 5.0);
  EXPECT_EQ(slam->tracker.close_points_gap_min_inliers, 100);
  EXPECT_EQ(slam->loop_closing.global_ba.first_pass_iterations, 30);
  EXPECT_EQ(slam->tracker.max_frames_between_keyframes,
            TrackerConfig{}.max_frames_between_keyframes);
}

// The KITTI example: the street settings and ORB-SLAM2's feature count for KITTI.
TEST(TrackerConfigTest, KittiExampleLoads) {
  std::string error;
  const std::optional<SlamSystemConfig> slam = loadSlamSettings(
      std::string(CBLOX_CONFIG_DIR) + "/examples/tracker_kitti.yaml", &error);
  ASSERT_TRUE(slam.has_value()) << error;
  EXPECT_EQ(slam->frames.orb.num_features, 2000);
  EXPECT_EQ(slam->tracker.reference_ratio, 0.5);
  EXPECT_EQ(slam->tracker.close_points_min_frames, 16);
  EXPECT_EQ(slam->tracker.close_points_turn_deg, 5.0);
  EXPECT_EQ(slam->tracker.close_points_gap_min_inliers, 100);
  EXPECT_EQ(slam->loop_closing.global_ba.first_pass_iterations, 30);
}

TEST(TrackerConfigTest, RejectsBadKeysAndValuesNamingThem) {
  struct Case {
    const char* yaml;
    const char* message;
  };
  const Case cases[] = {
      {"mdoe: stereo\n", "mdoe"},
      {"mode: mono\n", "mode"},
      {"initial_pose: gps\n", "initial_pose"},
      {"channels: {sterio: X}\n", "sterio"},
      {"channels: {stereo: ''}\n", "channel"},
      {"camera: {calibration: yaml}\n", "camera.calibration"},
      {"camera: {calibration: file}\n", "calibration_file"},
      {"camera: {calibration: file, calibration_file: /nonexistent/cam.yaml}\n",
       "/nonexistent/cam.yaml"},
      {"camera: {close_depth_baselines: 0}\n", "close_depth_baselines"},
      {"local_mapping: {disparity_correction: {windw: 3}}\n", "disparity_correction.windw"},
      {"local_mapping: {disparity_correction: {window: 3, min_estimates: 4}}\n",
       "min_estimates"},
      {"local_mapping: {disparity_correction: {max_landmarks: 0}}\n", "max_landmarks"},
      {"camera: {rgbd_baseline_m: -0.1}\n", "rgbd_baseline_m"},
      {"camera: {focal: 3}\n", "camera.focal"},
      {"frames: {orb: {num_features: 0}}\n", "frames.orb"},
      {"frames: {orb: {num_features: many}}\n", "frames.orb.num_features"},
      {"frames: {stereo: {min_depth_m: -1}}\n", "frames.stereo"},
      {"frames: {grid_cols: 0}\n", "grid_cols"},
      {"tracker: {min_pose_inliers: 0}\n", "min_pose_inliers"},
      {"tracker: {min_inliers: 3}\n", "tracker.min_inliers"},
      {"local_mapping: {min_found_ratio: 2}\n", "min_found_ratio"},
      {"local_mapping: {bundle_adjustment: {num_threads: 0}}\n", "bundle_adjustment"},
      {"loop_closing: {min_bow_matches: 1}\n", "min_bow_matches"},
      {"loop_closing: {seed: -1}\n", "loop_closing.seed"},
      {"loop_closing: {enabled: maybe}\n", "loop_closing.enabled"},
      {"input: {queue_capacity: 0}\n", "input.queue_capacity"},
      {"covariance: {method: magic}\n", "covariance.method"},
      {"covariance: {niceness: 20}\n", "covariance.niceness"},
      {"covariance: {max_queued_requests: 0}\n", "covariance.max_queued_requests"},
      {"input: {queue_capacity: 17}\n", "input.queue_capacity"},
      {"input: {ground_truth_wait_s: -1}\n", "ground_truth_wait_s"},
      {"image_check: {dark_level: 250}\n", "dark_level"},
      {"image_check: {max_fraction: 0}\n", "max_fraction"},
      {"status: {period_s: 0}\n", "period_s"},
      {"status: {timing_window: 0}\n", "status.timing_window"},
      {"status: {log_interval_s: 0}\n", "log_interval_s"},
      {"checkpoint: {period_s: -1}\n", "checkpoint.period_s"},
      {"checkpoint: {every: 3}\n", "checkpoint.every"},
  };
  for (const Case& c : cases) {
    try {
      loadTrackerConfig(YAML::Load(c.yaml));
      ADD_FAILURE() << "accepted: " << c.yaml;
    } catch (const ConfigError& e) {
      EXPECT_NE(std::string(e.what()).find(c.message), std::string::npos)
          << c.yaml << " -> " << e.what();
    }
  }
}

TEST(TrackerConfigTest, CalibrationFileOfTheSimulatorRig) {
  const std::string file = std::string(CBLOX_CONFIG_DIR) + "/calibration/sim_rig.yaml";
  const TrackerProcessConfig config = loadTrackerConfig(
      YAML::Load("camera: {calibration: file, calibration_file: '" + file + "'}\n"));
  ASSERT_TRUE(config.tracker.calibration.has_value());
  const RectifiedStereoCalibration& c = *config.tracker.calibration;
  // config/capture.yaml's rig (drivers/sim/sim_rig.h).
  EXPECT_EQ(c.intrinsics.width, 752);
  EXPECT_EQ(c.intrinsics.height, 480);
  EXPECT_EQ(c.intrinsics.fx, 458.0);
  EXPECT_EQ(c.intrinsics.fy, 458.0);
  EXPECT_EQ(c.intrinsics.cx, 375.5);
  EXPECT_EQ(c.intrinsics.cy, 239.5);
  EXPECT_NEAR(c.baseline_m, 0.11, 1e-15);
  EXPECT_TRUE(c.T_B_L.isApprox(Transformationd::Identity(), 0.0));
  // RGB-D mode reads cam0 only.
  TrackerProcessConfig rgbd = config;
  rgbd.tracker.mode = TrackerMode::kRgbd;
  finishTrackerConfig(&rgbd);
  EXPECT_EQ(rgbd.tracker.calibration->baseline_m, 0.0);
  // Back to message calibration: the file's is dropped.
  TrackerProcessConfig message = config;
  message.calibration_source = CalibrationSource::kMessage;
  finishTrackerConfig(&message);
  EXPECT_FALSE(message.tracker.calibration.has_value());
}

// A EuRoC-style pair (sensor.yaml fields under cam0 / cam1) after rectification: both cameras
// in the body frame with the same rotation, 0.11 m apart along the left camera's x.
const char* kEurocRectified = R"(
cam0:
  sensor_type: camera
  comment: rectified cam0
  T_BS:
    cols: 4
    rows: 4
    data: [0.0, -1.0, 0.0, -0.02, 1.0, 0.0, 0.0, -0.06, 0.0, 0.0, 1.0, 0.01, 0.0, 0.0, 0.0, 1.0]
  rate_hz: 20
  resolution: [752, 480]
  camera_model: pinhole
  intrinsics: [435.2, 435.2, 367.5, 252.2]
  distortion_model: radial-tangential
  distortion_coefficients: [0.0, 0.0, 0.0, 0.0]
cam1:
  T_BS:
    cols: 4
    rows: 4
    data: [0.0, -1.0, 0.0, -0.02, 1.0, 0.0, 0.0, 0.05, 0.0, 0.0, 1.0, 0.01, 0.0, 0.0, 0.0, 1.0]
  resolution: [752, 480]
  camera_model: pinhole
  intrinsics: [435.2, 435.2, 367.5, 252.2]
  distortion_coefficients: [0.0, 0.0, 0.0, 0.0]
)";

TEST(TrackerConfigTest, CalibrationFromEurocAndKalibrTransforms) {
  const RectifiedStereoCalibration euroc =
      parseCalibration(YAML::Load(kEurocRectified), "euroc", true);
  EXPECT_EQ(euroc.intrinsics.fx, 435.2);
  EXPECT_EQ(euroc.intrinsics.cy, 252.2);
  EXPECT_NEAR(euroc.baseline_m, 0.11, 1e-12);
  EXPECT_NEAR(euroc.T_B_L.translation().y(), -0.06, 1e-15);

  // Kalibr: T_cam_imu on both cameras (IMU in each camera); cam1 0.12 m along cam0's x.
  const char* kalibr = R"(
cam0:
  camera_model: pinhole
  intrinsics: [400, 401, 320, 240]
  resolution: [640, 480]
  T_cam_imu: [[1, 0, 0, 0.1], [0, 1, 0, 0], [0, 0, 1, 0], [0, 0, 0, 1]]
  rostopic: /cam0/image_rect
cam1:
  camera_model: pinhole
  intrinsics: [400, 401, 320, 240]
  resolution: [640, 480]
  T_cam_imu: [[1, 0, 0, -0.02], [0, 1, 0, 0], [0, 0, 1, 0], [0, 0, 0, 1]]
  timeshift_cam_imu: 0.0
)";
  const RectifiedStereoCalibration k = parseCalibration(YAML::Load(kalibr), "kalibr", true);
  EXPECT_EQ(k.intrinsics.fy, 401.0);
  EXPECT_NEAR(k.baseline_m, 0.12, 1e-12);
  EXPECT_NEAR(k.T_B_L.translation().x(), -0.1, 1e-15);  // T_imu_cam0 = T_cam0_imu^-1
}

TEST(TrackerConfigTest, CalibrationFileErrorsNameFileAndKey) {
  test::TempDir dir("cblox_tracker_calibration");
  // The real EuRoC cam0/cam1 sensor.yaml is of the raw, distorted camera: rejected.
  const std::string raw_path = (dir.path() / "raw.yaml").string();
  {
    std::ofstream out(raw_path);
    out << "%YAML:1.0\n"
           "cam0:\n  T_BS: {rows: 4, cols: 4, data: [1,0,0,0, 0,1,0,0, 0,0,1,0, 0,0,0,1]}\n"
           "  resolution: [752, 480]\n  camera_model: pinhole\n"
           "  intrinsics: [458.654, 457.296, 367.215, 248.375]\n"
           "  distortion_model: radial-tangential\n"
           "  distortion_coefficients: [-0.28340811, 0.07395907, 0.00019359, 1.76187114e-05]\n";
  }
  struct Case {
    std::string yaml;
    bool stereo;
    const char* message;
  };
  const std::string cam = "  intrinsics: [400, 400, 320, 240]\n  resolution: [640, 480]\n";
  const std::string identity = "[[1, 0, 0, 0], [0, 1, 0, 0], [0, 0, 1, 0], [0, 0, 0, 1]]";
  const Case cases[] = {
      {"cam1:\n" + cam, true, "cam0"},
      {"cam0:\n" + cam, true, "cam1"},
      {"cam0:\n" + cam + "cam1:\n" + cam, true, "T_cn_cnm1"},
      {"cam0:\n  intrinsics: [400, 400, 320]\n  resolution: [640, 480]\n", false,
       "cam0.intrinsics"},
      {"cam0:\n  intrinsics: [400, 400, 320, 240]\n  resolution: [640.5, 480]\n", false,
       "cam0.resolution"},
      {"cam0:\n  intrinsics: [-400, 400, 320, 240]\n  resolution: [640, 480]\n", false,
       "cam0.intrinsics"},
      {"cam0:\n" + cam + "  camera_model: omni\n", false, "camera_model"},
      {"cam0:\n" + cam + "  distortion_coeffs: [0.1, 0, 0, 0]\n", false, "distortion_coeffs"},
      {"cam0:\n" + cam + "  focal_length: 3\n", false, "cam0.focal_length"},
      {"cam0:\n" + cam + "cam2:\n" + cam, false, "cam2"},
      {"cam0:\n" + cam + "cam1:\n  intrinsics: [401, 400, 320, 240]\n  resolution: [640, 480]\n" +
           "  T_cn_cnm1: [[1, 0, 0, -0.1], [0, 1, 0, 0], [0, 0, 1, 0], [0, 0, 0, 1]]\n",
       true, "must equal the left camera's"},
      // Right camera rotated by 0.01 rad about y: not a rectified pair.
      {"cam0:\n" + cam + "cam1:\n" + cam +
           "  T_cn_cnm1: [[0.99995, 0, 0.0099998, -0.1], [0, 1, 0, 0], "
           "[-0.0099998, 0, 0.99995, 0], [0, 0, 0, 1]]\n",
       true, "rectified"},
      // Right camera to the left (negative baseline).
      {"cam0:\n" + cam + "cam1:\n" + cam +
           "  T_cn_cnm1: [[1, 0, 0, 0.1], [0, 1, 0, 0], [0, 0, 1, 0], [0, 0, 0, 1]]\n",
       true, "+baseline"},
      {"cam0:\n" + cam + "cam1:\n" + cam + "  T_cn_cnm1: [[2, 0, 0, 0], [0, 1, 0, 0], " +
           "[0, 0, 1, 0], [0, 0, 0, 1]]\n",
       true, "orthonormal"},
      {"cam0:\n" + cam + "  T_BS: {rows: 4, cols: 4, data: [1, 0]}\n  T_cam_imu: " + identity +
           "\n",
       false, "T_BS.data"},
  };
  for (const Case& c : cases) {
    try {
      parseCalibration(YAML::Load(c.yaml), "file.yaml", c.stereo);
      ADD_FAILURE() << "accepted: " << c.yaml;
    } catch (const ConfigError& e) {
      EXPECT_NE(std::string(e.what()).find(c.message), std::string::npos)
          << c.yaml << " -> " << e.what();
      EXPECT_EQ(std::string(e.what()).rfind("file.yaml", 0), 0u) << e.what();
    }
  }
  try {
    loadCalibrationFile(raw_path, false);
    ADD_FAILURE() << "accepted the raw EuRoC camera";
  } catch (const ConfigError& e) {
    EXPECT_NE(std::string(e.what()).find(raw_path + ".cam0.distortion_coefficients"),
              std::string::npos)
        << e.what();
  }
  try {
    loadCalibrationFile((dir.path() / "absent.yaml").string(), true);
    ADD_FAILURE() << "accepted a missing file";
  } catch (const ConfigError& e) {
    EXPECT_NE(std::string(e.what()).find("cannot open"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace cblox
