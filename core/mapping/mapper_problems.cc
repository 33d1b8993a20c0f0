#include "core/mapping/mapper_problems.h"

namespace cblox {

const char* inputProblemName(InputProblem problem) {
  switch (problem) {
    case InputProblem::kDepthUndecodable:
      return "depth_undecodable";
    case InputProblem::kDepthInvalid:
      return "depth_invalid";
    case InputProblem::kDepthOutOfOrder:
      return "depth_out_of_order";
    case InputProblem::kNoPose:
      return "no_pose";
    case InputProblem::kPoseTooOld:
      return "pose_too_old";
    case InputProblem::kPoseGap:
      return "pose_gap";
    case InputProblem::kAcrossJump:
      return "across_jump";
    case InputProblem::kTrackingLost:
      return "tracking_lost";
    case InputProblem::kWaitingForAnchor:
      return "waiting_for_anchor";
    case InputProblem::kIntegrationFailed:
      return "integration_failed";
    case InputProblem::kPoseUndecodable:
      return "pose_undecodable";
    case InputProblem::kPoseInvalid:
      return "pose_invalid";
    case InputProblem::kPoseDuplicate:
      return "pose_duplicate";
    case InputProblem::kPoseOutOfOrder:
      return "pose_out_of_order";
    case InputProblem::kKeyframeInvalid:
      return "keyframe_invalid";
    case InputProblem::kKeyframeDuplicate:
      return "keyframe_duplicate";
    case InputProblem::kKeyframePoseUnknown:
      return "keyframe_pose_unknown";
    case InputProblem::kKeyframePoseInvalid:
      return "keyframe_pose_invalid";
    case InputProblem::kMaintenanceDropped:
      return "maintenance_dropped";
    case InputProblem::kCovarianceReplyInvalid:
      return "covariance_reply_invalid";
    case InputProblem::kCommandInvalid:
      return "command_invalid";
    case InputProblem::kDistanceRequestInvalid:
      return "distance_request_invalid";
    case InputProblem::kCount:
      break;
  }
  return "?";
}

bool isFrameProblem(InputProblem problem) {
  return static_cast<int>(problem) <= static_cast<int>(InputProblem::kIntegrationFailed);
}

}  // namespace cblox
