#include "daemon/mapper/mapper_process_config.h"

#include <cmath>

namespace cblox {

std::string MapperProcessConfig::validate() const {
  if (std::string e = mapper.validate(); !e.empty()) return e;
  for (const std::string* channel :
       {&depth_channel, &ground_truth_channel, &frame_pose_channel, &keyframe_channel,
        &keyframe_poses_channel, &command_channel, &command_reply_channel, &map_status_channel,
        &heartbeat_channel, &covariance_request_channel, &covariance_reply_channel}) {
    if (channel->empty()) return "channels: a channel name is empty";
  }
  if (!(status_period_s > 0.0) || !std::isfinite(status_period_s)) {
    return "status.period_s must be finite and > 0";
  }
  if (std::string e = validateInputSilence(input_silence_s); !e.empty()) return e;
  if (!(progress_period_s > 0.0) || !std::isfinite(progress_period_s)) {
    return "status.progress_period_s must be finite and > 0";
  }
  return {};
}

}  // namespace cblox
