#pragma once

#include <string>

#include <yaml-cpp/yaml.h>

#include "daemon/mapper/mapper.h"

namespace cblox {

/// Settings of the cblox-mapper process (config/mapper.yaml): the Mapper's own settings
/// plus LCM, channels and reporting. Plain value type.
struct MapperProcessConfig {
  MapperConfig mapper;
  /// LCM provider URL; empty means LCM's default (udpm://239.255.76.67:7667?ttl=0).
  std::string lcm_url;
  std::string depth_channel = "CBLOX_DEPTH";
  std::string ground_truth_channel = "CBLOX_GT_POSE";
  std::string frame_pose_channel = "CBLOX_FRAME_POSE";
  std::string keyframe_channel = "CBLOX_KEYFRAME";
  std::string keyframe_poses_channel = "CBLOX_KEYFRAME_POSES";
  std::string command_channel = "CBLOX_CMD";
  std::string command_reply_channel = "CBLOX_CMD_REPLY";
  std::string map_status_channel = "CBLOX_MAP_STATUS";
  std::string heartbeat_channel = "CBLOX_HEARTBEAT";
  std::string covariance_request_channel = "CBLOX_COV_REQUEST";  ///< tracker mode
  std::string covariance_reply_channel = "CBLOX_COV_REPLY";      ///< tracker mode
  /// CBLOX_MAP_STATUS and CBLOX_HEARTBEAT period, seconds (> 0).
  double status_period_s = 1.0;
  /// Progress lines on stdout every this many seconds (> 0).
  double progress_period_s = 5.0;

  /// Empty when valid, otherwise a message naming the offending field. Thread-safe.
  std::string validate() const;
};

/// Parses "ground_truth" / "tracker"; throws ConfigError otherwise. Thread-safe.
PoseSource parsePoseSource(const std::string& name);

/// Reads the YAML tree of config/mapper.yaml over the defaults (absent keys keep the code's
/// defaults, including the mapper's own layer and integrator defaults); throws ConfigError
/// naming the key for unknown keys or bad values. Thread-safe.
MapperProcessConfig loadMapperConfig(const YAML::Node& root);

}  // namespace cblox
