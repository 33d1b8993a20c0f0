#pragma once

#include <cstddef>
#include <cstdint>
#include <optional>
#include <string>

#include <cblox/depth_frame_t.hpp>
#include <cblox/stereo_pair_t.hpp>

#include "core/geometry/image.h"
#include "core/geometry/stereo_rig.h"

namespace cblox {

/// Kinds of bad or untrackable input of cblox-tracker, each counted and logged once per
/// kind with rate limiting (the heartbeat carries one counter per kind).
enum class TrackerProblem : int {
  // Frames rejected before tracking (summed in frames_rejected; heartbeat "rejected_<name>"):
  kUndecodable = 0,     ///< the message does not decode (LCM wire format)
  kBadImage,            ///< bad image fields, a depth or unknown pixel format, no colour (RGB-D)
  kBadCalibration,      ///< invalid, not rectified, distorted, or T_L_R not a horizontal baseline
  kCalibrationChanged,  ///< valid, but not the calibration the tracker runs with
  kWrongSize,           ///< image size differs from the calibration's or the other image's
  kTimestampMismatch,   ///< left and right (colour and depth) image time stamps differ
  kOutOfOrder,          ///< frame_id or utime not increasing
  // Frames published LOST / NOT_INITIALIZED (heartbeat "untracked_<name>"):
  kDarkImage,         ///< nothing to track: (almost) black
  kSaturatedImage,    ///< nothing to track: (almost) white
  kTexturelessImage,  ///< nothing to track: (almost) uniform
  kNoGroundTruth,     ///< initial_pose ground_truth: the frame's pose did not arrive in time
  kNotInitialized,    ///< the tracker could not start its map on the frame (reason logged)
  kTrackingLost,      ///< the tracker lost track (its reason is logged)
  kTrackingFailed,    ///< the SLAM system threw (never expected)
  // Other messages (heartbeat "rejected_<name>"):
  kBadGroundTruth,        ///< CBLOX_GT_POSE that does not decode or holds an invalid pose
  kBadCovarianceRequest,  ///< CBLOX_COV_REQUEST that does not decode
  kCount
};
inline constexpr size_t kNumTrackerProblems = static_cast<size_t>(TrackerProblem::kCount);

/// Short snake_case name, e.g. "timestamp_mismatch". Thread-safe (pure).
const char* trackerProblemName(TrackerProblem problem);
/// True for the kinds that reject a frame before tracking. Thread-safe (pure).
bool isRejection(TrackerProblem problem);
/// The heartbeat counter of a kind: "rejected_<name>" or "untracked_<name>". Thread-safe.
std::string trackerProblemCounter(TrackerProblem problem);

/// One decoded input frame of the tracker. Plain value type.
struct TrackerFrame {
  int64_t frame_id = 0;
  int64_t utime = 0;  ///< capture time, microseconds
  GrayImage image;    ///< rectified left image, or the grey of the RGB-D colour image
  GrayImage right;    ///< stereo: rectified right image; RGB-D: empty
  DepthImage depth;   ///< RGB-D: metres, registered to `image`, 0 = none; stereo: empty
  /// The message's calibration (RGB-D: baseline_m 0, T_B_L = the depth camera in B); absent
  /// when it is invalid, and then calibration_error says why.
  std::optional<RectifiedStereoCalibration> calibration;
  std::string calibration_error;
  /// Set by TrackerNode::onFrame: the source restarted with time going back (a log or a
  /// simulator run again), so this frame starts a new map (the next map epoch).
  bool starts_new_map = false;
};

/// Decodes a CBLOX_STEREO message: images (GRAY8, or colour converted to grey), the
/// calibration (fromStereoCalibrationMsg; a bad one is left for the caller to judge, since a
/// configured calibration overrides it). Returns false with the problem kind and a message
/// for bad images (kBadImage), left/right time stamps that differ (kTimestampMismatch) and
/// images of different sizes (kWrongSize). Thread-safe (pure).
bool decodeStereoPair(const stereo_pair_t& msg, TrackerFrame* frame, TrackerProblem* problem,
                      std::string* error);

/// Decodes a CBLOX_DEPTH message for RGB-D tracking: depth (readings outside the message's
/// [min_depth_m, max_depth_m] become 0), the registered colour image as grey (required:
/// kBadImage without it), the depth camera's calibration. Returns false with the kind and a
/// message as decodeStereoPair does (colour and depth time stamps and sizes must agree).
/// Thread-safe (pure).
bool decodeRgbdFrame(const depth_frame_t& msg, TrackerFrame* frame, TrackerProblem* problem,
                     std::string* error);

}  // namespace cblox
