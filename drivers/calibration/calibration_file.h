#pragma once

#include <stdexcept>
#include <string>

#include <yaml-cpp/yaml.h>

#include "drivers/calibration/stereo_calibration.h"

namespace cblox {

/// A calibration file that cannot be used; what() starts with the file (and key) at fault.
class CalibrationError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

/// Reads the calibration of a camera or stereo pair, raw (distorted, unrectified) or already
/// rectified, from either of the two formats people have:
///
/// 1. Kalibr camchain YAML (also EuRoC's sensor.yaml fields), one map per camera:
///
///      cam0:                                  # the left camera (or the only one)
///        camera_model: pinhole                # optional; only pinhole
///        intrinsics: [fu, fv, pu, pv]         # pixels
///        resolution: [width, height]          # pixels
///        distortion_model: radtan             # radtan | radial-tangential | equidistant |
///                                             # none; optional (radtan)
///        distortion_coeffs: [k1, k2, p1, p2]  # Kalibr name; EuRoC: distortion_coefficients
///        T_BS: {rows: 4, cols: 4, data: [..]} # optional, EuRoC: camera in the body frame
///        T_cam_imu: [[...], ... 4 rows]       # optional, Kalibr: body (IMU) in the camera
///      cam1:                                  # the right camera (stereo only)
///        same fields, and T_cn_cnm1           # Kalibr: cam0 in cam1 (T_R_L); or T_BS /
///                                             # T_cam_imu on both cameras
///
///    Kalibr's and EuRoC's other fields (rostopic, sensor_type, comment, rate_hz,
///    cam_overlaps, timeshift_cam_imu) are accepted and ignored; anything else is an error.
///
/// 2. OpenCV FileStorage, YAML ("%YAML:1.0"), XML or JSON, as written by OpenCV's stereo_calib
///    sample and `cblox-calib calibrate`: camera matrices M1, M2 (or K1, K2), distortion D1,
///    D2 (plumb-bob), R and T from cv::stereoCalibrate (p_R = R p_L + T, metres), the image
///    size as image_width and image_height (or imageSize / image_size: [w, h]), and an
///    optional distortion_model ("radtan" or "equidistant" for cv::fisheye). When R and T are
///    not in the file but an extrinsics.yml|.yaml|.xml sits beside it (the sample's pair of
///    files), they are read from there.
///
/// The file is read by readOpenCvStorage (opencv_storage.h: YAML, XML or JSON by content,
/// at most 1 MiB, never by OpenCV's own parsers); a top level with cam0 is a camchain, any
/// other OpenCV's. With `stereo` false only the left camera is read (the right stays
/// default). Throws CalibrationError naming the file and key. Thread-safe.
StereoCameraCalibration loadStereoCalibration(const std::string& path, bool stereo);

/// As loadStereoCalibration, for a camchain already parsed; `where` prefixes messages.
/// Throws CalibrationError. Thread-safe.
StereoCameraCalibration parseCamchain(const YAML::Node& root, const std::string& where,
                                      bool stereo);

}  // namespace cblox
