#pragma once

#include <string>

#include <Eigen/Core>

#include "core/geometry/pinhole_camera.h"
#include "core/geometry/se3.h"
#include "core/geometry/stereo_rig.h"

namespace cblox {

/// The simulated sensor head: a rectified stereo pair (left camera L = the rig's body frame)
/// and a depth camera D with its own intrinsics and pose in L. The default depth camera is
/// registered to the left camera (same intrinsics, identity extrinsics), like an RGB-D
/// sensor's depth aligned to its colour image. Plain value type.
struct SimRigConfig {
  /// Rectified intrinsics of both stereo cameras (EuRoC-like 752x480 by default).
  PinholeIntrinsics stereo{458.0, 458.0, 375.5, 239.5, 752, 480};
  /// Right camera at (+baseline_m, 0, 0) in L.
  double baseline_m = 0.11;
  /// Calibration error, pixels in [-10, 10]: the right image is rendered with its principal
  /// point this far right of the calibration's (cx + right_cx_error_px), which
  /// stereoCalibration() does not know, as after a rectification whose right camera is off.
  /// Every disparity is then this much smaller than fx * baseline_m / z: depths are too large,
  /// by more the farther the point. 0 = exact calibration.
  double right_cx_error_px = 0.0;
  /// Depth camera intrinsics; width == 0 means "the same as the stereo cameras".
  PinholeIntrinsics depth{0.0, 0.0, 0.0, 0.0, 0, 0};
  /// Depth camera pose in the left camera frame.
  Transformationd T_L_D;
  /// Depth readings outside [depth_min_m, depth_max_m] (z, metres) are reported as 0.
  double depth_min_m = 0.1;
  double depth_max_m = 10.0;

  /// Empty when valid, else a message naming the first bad field. Thread-safe.
  std::string validate() const;
  /// The depth camera's intrinsics (the stereo ones when `depth.width == 0`). Thread-safe.
  PinholeIntrinsics depthIntrinsics() const;
  /// True when the depth camera coincides with the left camera (same intrinsics, identity
  /// extrinsics), so one render serves both. Thread-safe.
  bool depthIsLeftCamera() const;
  /// The intrinsics the right image is rendered with: `stereo` with cx + right_cx_error_px.
  /// Thread-safe.
  PinholeIntrinsics rightIntrinsics() const;
  /// The stereo calibration of the rig (T_B_L = identity: the body is the left camera).
  RectifiedStereoCalibration stereoCalibration() const;
};

/// Light for shading: ambient + diffuse * (1 + n . l) / 2 (hemispherical: surfaces facing
/// away from the light are dimmer but never black); view-independent, so both stereo cameras
/// see the same brightness at a surface point. Plain value type.
struct SimLightingConfig {
  /// Direction towards the light in the world frame (normalised on use; z is up).
  Eigen::Vector3d towards_light_G{0.35, 0.25, 1.0};
  double ambient = 0.55;
  double diffuse = 0.55;
  /// Grey value of pixels that see nothing (sky / beyond the scene).
  int background_gray = 190;

  std::string validate() const;
};

}  // namespace cblox
