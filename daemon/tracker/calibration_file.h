#pragma once

#include <string>

#include <yaml-cpp/yaml.h>

#include "core/geometry/stereo_rig.h"

namespace cblox {

/// Reads the tracker's camera calibration from a YAML file in the style of Kalibr's camchain
/// or EuRoC's sensor.yaml, one map per camera:
///
///   cam0:                                   # the (rectified) left camera, or the RGB-D camera
///     camera_model: pinhole                 # optional; only pinhole
///     intrinsics: [fu, fv, pu, pv]          # pixels
///     resolution: [width, height]           # pixels
///     distortion_model: radtan              # optional; the coefficients must all be 0
///     distortion_coeffs: [0, 0, 0, 0]       # Kalibr name; EuRoC: distortion_coefficients
///     T_BS: {rows: 4, cols: 4, data: [...]} # optional, EuRoC: camera in the body frame
///     T_cam_imu: [[...], [...], [...], [...]]  # optional, Kalibr: body (IMU) in the camera
///   cam1:                                   # the rectified right camera (stereo only)
///     intrinsics / resolution / distortion as cam0 (must equal cam0's)
///     T_cn_cnm1: [[...], ...]               # Kalibr: cam0 in cam1 (T_R_L); or T_BS /
///                                           # T_cam_imu on both cameras
///
/// The tracker does not rectify: the file must describe the rectified pair the capture
/// publishes (no distortion, equal intrinsics, right camera at (+baseline, 0, 0) in the left
/// one without rotation, within 1e-6). Kalibr's and EuRoC's other fields (rostopic,
/// sensor_type, comment, rate_hz, cam_overlaps, timeshift_cam_imu) are accepted and ignored;
/// anything else is an error. A leading "%YAML:1.0" line (OpenCV) is skipped.
///
/// Returns the intrinsics, the baseline (0 when `stereo` is false: cam1 is then ignored) and
/// T_B_L (from T_BS or T_cam_imu of cam0; identity without them). Throws ConfigError naming
/// the file and key. Thread-safe.
RectifiedStereoCalibration loadCalibrationFile(const std::string& path, bool stereo);

/// As loadCalibrationFile, from a parsed YAML tree; `where` prefixes messages.
RectifiedStereoCalibration parseCalibration(const YAML::Node& root, const std::string& where,
                                            bool stereo);

}  // namespace cblox
