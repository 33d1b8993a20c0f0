#pragma once

#include <optional>
#include <string>

#include <yaml-cpp/yaml.h>

#include "daemon/common/input_silence.h"
#include "daemon/tracker/tracker_node.h"

namespace cblox {

/// Where the tracker's camera calibration comes from.
enum class CalibrationSource {
  kMessage,  ///< each frame's message (the first valid frame fixes it for the run)
  kFile,     ///< camera.calibration_file (Kalibr / EuRoC style, see calibration_file.h)
};

/// Settings of the cblox-tracker process (config/tracker.yaml): the TrackerNode's settings
/// (with the SLAM system's) plus LCM, channels, vocabulary and reporting. Plain value type.
struct TrackerProcessConfig {
  TrackerNodeConfig tracker;
  /// LCM provider URL; empty means LCM's default (udpm://239.255.76.67:7667?ttl=0).
  std::string lcm_url;
  /// Place-recognition vocabulary file: empty = the one trained at build time
  /// (CBLOX_DEFAULT_VOCABULARY); "none" = no vocabulary (no relocalization, no loop closing).
  std::string vocabulary;
  CalibrationSource calibration_source = CalibrationSource::kMessage;
  /// The calibration file (calibration_source kFile); relative to the working directory.
  std::string calibration_file;
  std::string stereo_channel = "CBLOX_STEREO";
  std::string depth_channel = "CBLOX_DEPTH";
  std::string ground_truth_channel = "CBLOX_GT_POSE";
  std::string frame_pose_channel = "CBLOX_FRAME_POSE";
  std::string keyframe_channel = "CBLOX_KEYFRAME";
  std::string keyframe_poses_channel = "CBLOX_KEYFRAME_POSES";
  std::string heartbeat_channel = "CBLOX_HEARTBEAT";
  std::string covariance_request_channel = "CBLOX_COV_REQUEST";  ///< from the mapper
  std::string covariance_reply_channel = "CBLOX_COV_REPLY";      ///< to the mapper
  /// CBLOX_HEARTBEAT period, seconds (> 0).
  double status_period_s = 1.0;
  /// Progress lines on stdout every this many seconds (> 0).
  double progress_period_s = 5.0;
  /// Input-silence health (daemon/common/input_watch.h): the heartbeat reports the frame
  /// channel (stereo or depth, by mode) silent after this long without a message, seconds;
  /// 0 = off.
  double input_silence_s = kDefaultInputSilenceS;

  /// Empty when valid, otherwise a message naming the offending field. Thread-safe.
  std::string validate() const;
};

/// Parse "stereo" / "rgbd", "identity" / "ground_truth"; throw ConfigError otherwise.
/// Thread-safe.
TrackerMode parseTrackerMode(const std::string& name);
InitialPose parseInitialPose(const std::string& name);

/// Reads the YAML tree of config/tracker.yaml over the defaults (absent keys keep the code's
/// defaults), then finishTrackerConfig(); throws ConfigError naming the key for unknown keys
/// or bad values. Thread-safe.
TrackerProcessConfig loadTrackerConfig(const YAML::Node& root);

/// The SLAM settings (TrackerNodeConfig::slam) of the tracker.yaml at `path`, read by
/// loadTrackerConfig(), for tools that run the SLAM system without the process
/// (cblox-bench-slam and cblox-bench-maintenance --config); an empty path gives the defaults
/// (no file). Returns std::nullopt and, when error is non-null, "<path>: <what>" when the
/// file cannot be read or parsed or a key or value is bad. Thread-safe.
std::optional<SlamSystemConfig> loadSlamSettings(const std::string& path, std::string* error);
/// The same for the whole tracking part (TrackerNodeConfig: the SLAM settings and the SLAM
/// threads' niceness, which cblox-bench-slam applies as the process does).
std::optional<TrackerNodeConfig> loadTrackerNodeSettings(const std::string& path,
                                                         std::string* error);

/// Loads the calibration file into config->tracker.calibration when calibration_source is
/// kFile (cleared otherwise; for the configured mode: cam1 only for stereo) and validates the
/// whole config. Call again after command-line overrides. Throws ConfigError naming the key.
void finishTrackerConfig(TrackerProcessConfig* config);

}  // namespace cblox
