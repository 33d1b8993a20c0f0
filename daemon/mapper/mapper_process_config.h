#pragma once

// Settings of the cblox-mapper process: the dense mapper's own settings (MapperConfig) plus
// LCM, channels and reporting. YAML loading is in mapper_config_loader.h.

#include <string>

#include "core/mapping/mapper_config.h"
#include "daemon/common/input_silence.h"

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
  std::string distance_request_channel = "CBLOX_DISTANCE_REQUEST";  ///< planners ask
  std::string distance_reply_channel = "CBLOX_DISTANCE_REPLY";      ///< the mapper answers
  std::string local_grid_channel = "CBLOX_LOCAL_GRID";              ///< planning.local_grid_*
  std::string mesh_update_channel = "CBLOX_MESH_UPDATE";  ///< mesh_stream: changed blocks
  std::string subvolumes_channel = "CBLOX_SUBVOLUMES";    ///< mesh_stream: subvolume poses
  /// CBLOX_MAP_STATUS and CBLOX_HEARTBEAT period, seconds (> 0).
  double status_period_s = 1.0;
  /// Progress lines on stdout every this many seconds (> 0).
  double progress_period_s = 5.0;
  /// Input-silence health (daemon/common/input_watch.h): the heartbeat reports CBLOX_DEPTH or
  /// the pose channel (CBLOX_GT_POSE or CBLOX_FRAME_POSE, by pose source) silent after this
  /// long without a message, seconds; 0 = off (finite, >= 0; checked by loadMapperConfig).
  double input_silence_s = kDefaultInputSilenceS;

  /// Empty when valid, otherwise a message naming the offending field. Thread-safe.
  std::string validate() const;
};

}  // namespace cblox
