#pragma once

#include "core/geometry/pinhole_camera.h"
#include "core/geometry/se3.h"

namespace cblox {

/// Calibration of a rectified, horizontal stereo pair: both images share `intrinsics` (no
/// distortion), epipolar lines are image rows, and the right camera R sits at
/// (+baseline_m, 0, 0) in the left camera frame L with the same orientation, so a point at
/// depth z has disparity u_left - u_right = fx * baseline_m / z. Plain value type.
struct RectifiedStereoCalibration {
  PinholeIntrinsics intrinsics;
  double baseline_m = 0.0;
  /// Rectified left camera in the rig's body frame B (identity when B is the left camera).
  Transformationd T_B_L;
};

}  // namespace cblox
