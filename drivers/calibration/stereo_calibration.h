#pragma once

#include <optional>
#include <string>
#include <vector>

#include "core/geometry/pinhole_camera.h"
#include "core/geometry/se3.h"

namespace cblox {

/// Lens distortion of a raw camera, in OpenCV's conventions.
enum class DistortionModel {
  kNone,         ///< already undistorted
  kRadTan,       ///< OpenCV's plumb-bob: k1 k2 p1 p2 [k3 [k4 k5 k6 [s1 s2 s3 s4 [tx ty]]]]
  kEquidistant,  ///< OpenCV's fisheye / Kalibr's equidistant: k1 k2 k3 k4
};

/// "none", "radtan", "equidistant". Thread-safe (pure).
const char* distortionModelName(DistortionModel model);

/// One raw (distorted, unrectified) camera of a rig. Plain value type.
struct CameraCalibration {
  PinholeIntrinsics intrinsics;  ///< raw pinhole intrinsics; width/height = image size
  DistortionModel distortion = DistortionModel::kNone;
  std::vector<double> distortion_coefficients;  ///< see DistortionModel for the order
  /// Camera C in the rig's body frame B, when the file gives one (EuRoC T_BS, Kalibr
  /// T_cam_imu inverted).
  std::optional<Transformationd> T_B_C;
  /// Where the distortion was read from, e.g. "rig.yaml.cam0.distortion_coeffs"; for messages.
  std::string distortion_key;
};

/// A raw stereo pair as calibrated (Kalibr camchain, OpenCV stereoCalibrate). Plain value type.
struct StereoCameraCalibration {
  CameraCalibration left, right;
  /// The left camera in the right camera's frame: p_R = T_R_L * p_L (Kalibr's cam1 T_cn_cnm1,
  /// OpenCV's stereoCalibrate R and T).
  Transformationd T_R_L;
  std::string source;  ///< the file it was read from, for messages
};

/// Returns "" if the camera is usable, else a message naming the first bad field: valid
/// intrinsics, coefficient count 4, 5, 8, 12 or 14 for radtan, 4 for equidistant, 0 or all-zero
/// for none, all finite. Thread-safe (pure).
std::string validate(const CameraCalibration& camera);

/// True when every distortion coefficient is 0 (or there is none). Thread-safe (pure).
bool isUndistorted(const CameraCalibration& camera);

/// True when a and b have the same size and fx, fy, cx, cy within `tolerance` pixels.
/// Thread-safe (pure).
bool sameIntrinsics(const PinholeIntrinsics& a, const PinholeIntrinsics& b, double tolerance);

/// "" when the pair's geometry is already that of a rectified pair (equal intrinsics within
/// `tolerance` px, the right camera at (+b, 0, 0) in the left one without rotation within
/// `tolerance` m and rad), else why not, e.g. "the right camera must sit at (+baseline, 0, 0)
/// in the left one without rotation (a rectified pair); it is at (0.1, 0.01, 0) m, rotated by
/// 0 rad". Distortion is not looked at (isUndistorted()). Thread-safe (pure).
std::string rectifiedPairProblem(const StereoCameraCalibration& pair, double tolerance);

}  // namespace cblox
