#pragma once

#include <string>

#include "core/optimization/bundle_adjustment.h"

namespace cblox {

/// Settings of estimateDisparityOffset(). Plain value type.
struct DisparityOffsetSolverConfig {
  /// Levenberg-Marquardt iterations, >= 1.
  int iterations = 10;
  /// Stereo observations needed, >= 1: fewer give no estimate.
  int min_stereo_observations = 200;
  /// Landmarks used at the most (the first ones of the problem with a stereo observation),
  /// >= 1: bounds the time of a solve.
  int max_landmarks = 600;

  /// Empty when valid, else a message naming the first bad field. Thread-safe.
  std::string validate() const;
};

/// What estimateDisparityOffset() found. Plain value type.
struct DisparityOffsetEstimate {
  bool ok = false;            ///< false: `reason` says why there is no estimate
  std::string reason;
  double offset_px = 0.0;     ///< c, level-0 pixels (see estimateDisparityOffset)
  int stereo_observations = 0;
  int landmarks = 0;
  double initial_cost = 0.0;  ///< Ceres' costs (1/2 sum of robust chi2) at c = 0 and at the end
  double final_cost = 0.0;
};

/// The stereo rig's disparity offset c, estimated with the bundle adjustment of `problem`:
/// every right-image measurement is modelled as u_right = u - bf / z + c, i.e. as taken by a
/// right camera whose principal point lies c pixels right of the calibration's (a
/// rectification error; a positive c makes every measured disparity c pixels too small and
/// every stereo depth too large, by more the farther the point). The poses of the keyframes
/// that are not fixed, the landmarks and c are optimised together (Huber loss as in
/// bundleAdjust, landmarks eliminated first); c starts at 0. `problem` must hold the raw
/// measurements, as matched, not corrected by an earlier estimate.
///
/// c is observable only through the monocular geometry of several views: the left images
/// fix each landmark's depth up to the window's scale, and stereo then gives scale and c
/// together when the landmarks' depths vary. A window of one depth, or without parallax,
/// leaves c undetermined: use the estimate of many windows (DisparityCorrection).
/// Returns ok = false with a reason for an invalid problem or config, no fixed keyframe,
/// fewer stereo observations than configured, or a failed solve. Thread-safe (pure).
DisparityOffsetEstimate estimateDisparityOffset(const BundleAdjustmentProblem& problem,
                                                const DisparityOffsetSolverConfig& config);

}  // namespace cblox
