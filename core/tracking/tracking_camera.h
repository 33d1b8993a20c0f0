#pragma once

#include <string>

#include "core/geometry/pinhole_camera.h"

namespace cblox {

/// The camera the tracker works in: the rectified left camera of a stereo pair, or an RGB-D
/// camera treated as a virtual stereo rig (ORB-SLAM2's RGB-D mode: a feature of depth z gets
/// the virtual right coordinate u - bf / z). Plain value type.
struct TrackingCamera {
  PinholeIntrinsics intrinsics;  ///< rectified, no distortion; image size in pixels
  /// Stereo baseline in metres (> 0). For RGB-D the virtual baseline only weights the third
  /// residual (u_right) of a measurement; ORB-SLAM2 configures bf directly.
  double baseline_m = 0.0;
  /// Features closer than this (metres) are "close": their stereo depth is trusted enough to
  /// create landmarks from a single frame (ORB-SLAM2's ThDepth, 35-40 baselines).
  double close_depth_m = 0.0;

  /// fx * baseline, in pixel metres: disparity = bf / depth.
  double bf() const { return intrinsics.fx * baseline_m; }

  /// Empty when valid, else a message naming the field. Thread-safe.
  std::string validate() const;
};

/// ORB-SLAM2's close/far split (ThDepth): 40 baselines.
inline constexpr double kDefaultCloseDepthBaselines = 40.0;

/// The tracking camera of rectified intrinsics and a (real or virtual) baseline in metres,
/// with close_depth_m = close_depth_baselines * baseline_m. Does not validate. Thread-safe.
inline TrackingCamera makeTrackingCamera(
    const PinholeIntrinsics& intrinsics, double baseline_m,
    double close_depth_baselines = kDefaultCloseDepthBaselines) {
  TrackingCamera camera;
  camera.intrinsics = intrinsics;
  camera.baseline_m = baseline_m;
  camera.close_depth_m = close_depth_baselines * baseline_m;
  return camera;
}

}  // namespace cblox
