#pragma once

// The kinds of bad or unusable input the mapper counts (MapperStatus::problems, heartbeat
// "rejected_<name>").

#include <cstddef>

namespace cblox {

/// Kinds of bad or unusable input, each counted (MapperStatus::problems) and logged once per
/// kind with rate limiting.
enum class InputProblem : int {
  // Depth frames (counted in frames_rejected):
  kDepthUndecodable = 0,  ///< the depth message failed to decode (reported by the adapter)
  kDepthInvalid,          ///< bad intrinsics, sizes that disagree, non-finite extrinsics
  kDepthOutOfOrder,       ///< time stamp not newer than the previous depth frame's
  kNoPose,                ///< no pose arrived within max_pose_wait_s
  kPoseTooOld,            ///< older than every pose kept
  kPoseGap,               ///< the poses around it are further apart than the gap bound
  kAcrossJump,            ///< a tracking jump or epoch change lies between its poses
  kTrackingLost,          ///< a pose around it is LOST / NOT_INITIALIZED
  kWaitingForAnchor,      ///< after a tracking jump / before the first keyframe
  kIntegrationFailed,     ///< the integrator threw (never expected; the frame is dropped)
  // Poses, keyframes, batches, commands (not frames):
  kPoseUndecodable,         ///< pose message failed to decode, unknown tracking state
  kPoseInvalid,             ///< non-finite pose or non-unit quaternion
  kPoseDuplicate,           ///< same time stamp as the previous pose
  kPoseOutOfOrder,          ///< older than the previous pose
  kKeyframeInvalid,         ///< non-finite keyframe pose or undecodable keyframe message
  kKeyframeDuplicate,       ///< keyframe id already applied
  kKeyframePoseUnknown,     ///< batch entry for a keyframe no subvolume knows
  kKeyframePoseInvalid,     ///< batch entry with a non-finite pose; undecodable batch
  kMaintenanceDropped,      ///< keyframe / batch dropped because the queue was full
  kCovarianceReplyInvalid,  ///< covariance reply failed to decode or has a bad entry
  kCommandInvalid,          ///< unknown command, missing or bad argument, path outside
  kDistanceRequestInvalid,  ///< distance request failed to decode or has too many points
  kCount
};
inline constexpr size_t kNumInputProblems = static_cast<size_t>(InputProblem::kCount);
/// Short snake_case name of a problem kind, e.g. "pose_gap" (heartbeat counter names).
/// Thread-safe (pure).
const char* inputProblemName(InputProblem problem);
/// True for the kinds that reject a depth frame (summed in frames_rejected). Thread-safe.
bool isFrameProblem(InputProblem problem);

}  // namespace cblox
