#include "daemon/tracker/tracker_input.h"

#include <cmath>
#include <iterator>

#include "daemon/common/lcm_messages.h"

namespace cblox {
namespace {

bool fail(TrackerProblem kind, std::string message, TrackerProblem* problem, std::string* error) {
  if (problem != nullptr) *problem = kind;
  if (error != nullptr) *error = std::move(message);
  return false;
}

std::string sizeText(int width, int height) {
  return std::to_string(width) + "x" + std::to_string(height);
}

}  // namespace

const char* trackerProblemName(TrackerProblem problem) {
  static constexpr const char* kNames[] = {
      "undecodable",     "bad_image",          "bad_calibration",  "calibration_changed",
      "wrong_size",      "timestamp_mismatch", "out_of_order",     "dark_image",
      "saturated_image", "textureless_image",  "no_ground_truth",  "not_initialized",
      "tracking_lost",   "tracking_failed",    "bad_ground_truth", "bad_covariance_request"};
  static_assert(std::size(kNames) == kNumTrackerProblems);
  const size_t index = static_cast<size_t>(problem);
  return index < kNumTrackerProblems ? kNames[index] : "unknown";
}

bool isRejection(TrackerProblem problem) {
  return static_cast<int>(problem) <= static_cast<int>(TrackerProblem::kOutOfOrder);
}

std::string trackerProblemCounter(TrackerProblem problem) {
  const bool rejected = isRejection(problem) || problem == TrackerProblem::kBadGroundTruth ||
                        problem == TrackerProblem::kBadCovarianceRequest;
  return std::string(rejected ? "rejected_" : "untracked_") + trackerProblemName(problem);
}

bool decodeStereoPair(const stereo_pair_t& msg, TrackerFrame* frame, TrackerProblem* problem,
                      std::string* error) {
  frame->frame_id = msg.frame_id;
  frame->utime = msg.utime;
  std::string why;
  if (!fromImageMsg(msg.left, &frame->image, &why)) {
    return fail(TrackerProblem::kBadImage, "left: " + why, problem, error);
  }
  if (!fromImageMsg(msg.right, &frame->right, &why)) {
    return fail(TrackerProblem::kBadImage, "right: " + why, problem, error);
  }
  if (msg.left.utime != msg.right.utime) {
    return fail(TrackerProblem::kTimestampMismatch,
                "left image at " + std::to_string(msg.left.utime) + " us, right at " +
                    std::to_string(msg.right.utime) + " us",
                problem, error);
  }
  if (!frame->image.sameSize(frame->right)) {
    return fail(TrackerProblem::kWrongSize,
                "left image " + sizeText(frame->image.width, frame->image.height) +
                    ", right image " + sizeText(frame->right.width, frame->right.height),
                problem, error);
  }
  frame->depth = DepthImage();
  frame->calibration = fromStereoCalibrationMsg(msg, &frame->calibration_error);
  if (frame->calibration) frame->calibration_error.clear();
  return true;
}

bool decodeRgbdFrame(const depth_frame_t& msg, TrackerFrame* frame, TrackerProblem* problem,
                     std::string* error) {
  frame->frame_id = msg.frame_id;
  frame->utime = msg.utime;
  std::string why;
  if (!fromDepthImageMsg(msg.depth, &frame->depth, &why)) {
    return fail(TrackerProblem::kBadImage, "depth: " + why, problem, error);
  }
  if (!msg.has_color) {
    return fail(TrackerProblem::kBadImage,
                "RGB-D tracking needs the registered colour image (has_color is false)", problem,
                error);
  }
  if (!fromImageMsg(msg.color, &frame->image, &why)) {
    return fail(TrackerProblem::kBadImage, "colour: " + why, problem, error);
  }
  if (msg.depth.utime != msg.color.utime) {
    return fail(TrackerProblem::kTimestampMismatch,
                "depth image at " + std::to_string(msg.depth.utime) + " us, colour at " +
                    std::to_string(msg.color.utime) + " us",
                problem, error);
  }
  if (!frame->image.sameSize(frame->depth)) {
    return fail(TrackerProblem::kWrongSize,
                "depth image " + sizeText(frame->depth.width, frame->depth.height) +
                    ", colour image " + sizeText(frame->image.width, frame->image.height),
                problem, error);
  }
  const float min_depth = msg.min_depth_m, max_depth = msg.max_depth_m;
  if (std::isfinite(min_depth) && std::isfinite(max_depth) && max_depth > min_depth) {
    for (float& d : frame->depth.data) {
      if (d < min_depth || d > max_depth) d = 0.0f;
    }
  }
  frame->right = GrayImage();
  frame->calibration.reset();
  frame->calibration_error.clear();
  const std::optional<PinholeIntrinsics> intrinsics =
      fromCalibrationMsg(msg.calibration, &frame->calibration_error);
  const std::optional<Transformationd> T_B_D =
      intrinsics ? fromPoseMsg(msg.calibration.T_B_C, &frame->calibration_error) : std::nullopt;
  if (intrinsics && !T_B_D)
    frame->calibration_error = "calibration.T_B_C: " + frame->calibration_error;
  if (T_B_D) {
    frame->calibration = RectifiedStereoCalibration{*intrinsics, 0.0, *T_B_D};
    frame->calibration_error.clear();
  }
  return true;
}

}  // namespace cblox
