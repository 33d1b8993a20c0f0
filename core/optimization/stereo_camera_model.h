#pragma once

#include <string>

#include "core/geometry/stereo_rig.h"

namespace cblox {

/// Rectified stereo pinhole camera, the model of ORB-SLAM2's stereo/RGB-D optimisers.
///
/// Frame C is the rectified left camera: x right, y down, z forward (metres). A point
/// p_C = (x, y, z) with z > 0 projects to the left image at
///   u = fx * x / z + cx,   v = fy * y / z + cy          (pixels)
/// and to the right image column
///   u_right = u - bf / z,                              (pixels)
/// where bf = fx * baseline (pixels * metres). In RGB-D mode u_right is a "virtual" right
/// coordinate computed from the measured depth with the same bf.
///
/// Observations used by the optimisers carry (u, v, u_right, inv_sigma2):
///  - a "stereo" observation has u_right >= 0 and gives 3 residuals (u, v, u_right);
///  - a "mono" observation has u_right < 0 and gives 2 residuals (u, v);
///  - inv_sigma2 > 0 is the information scale of the keypoint, 1 / scale^(2 * octave) for an
///    ORB pyramid with scale factor `scale`: the residual's information matrix is
///    inv_sigma2 * I, so chi2 = inv_sigma2 * |measured - projected|^2.
/// Plain value type; thread-safe.
struct StereoCameraModel {
  double fx = 0.0;  ///< focal length, pixels (> 0)
  double fy = 0.0;  ///< focal length, pixels (> 0)
  double cx = 0.0;  ///< principal point column, pixels
  double cy = 0.0;  ///< principal point row, pixels
  double bf = 0.0;  ///< fx * baseline, pixels * metres (> 0)
};

/// Empty if the model is usable, else a message naming the first bad field, e.g.
/// "bf must be > 0, got 0". Requires finite fx, fy, bf > 0 and finite cx, cy.
/// Thread-safe (pure).
std::string validate(const StereoCameraModel& camera);

/// The model of a rectified stereo calibration: fx, fy, cx, cy of the shared intrinsics and
/// bf = fx * baseline_m. Does not validate. Thread-safe (pure).
StereoCameraModel stereoCameraModelFrom(const RectifiedStereoCalibration& calibration);

}  // namespace cblox
