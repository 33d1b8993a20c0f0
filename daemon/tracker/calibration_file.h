#pragma once

#include <string>

#include <yaml-cpp/yaml.h>

#include "core/geometry/stereo_rig.h"

namespace cblox {

/// Reads the tracker's camera calibration from a file in any format loadStereoCalibration
/// reads (drivers/calibration/calibration_file.h: Kalibr camchain, EuRoC sensor.yaml fields,
/// OpenCV YAML/XML).
///
/// The tracker does not rectify: the file must describe the rectified pair the capture
/// publishes (no distortion, equal intrinsics, right camera at (+baseline, 0, 0) in the left
/// one without rotation, within 1e-6). A raw rig's file goes to cblox-capture instead
/// (`calibration:` in config/capture.yaml), which rectifies and publishes the rectified
/// calibration on CBLOX_STEREO.
///
/// Returns the intrinsics, the baseline (0 when `stereo` is false: cam1 is then ignored) and
/// T_B_L (from T_BS or T_cam_imu of cam0; identity without them). Throws ConfigError naming
/// the file and key. Thread-safe.
RectifiedStereoCalibration loadCalibrationFile(const std::string& path, bool stereo);

/// As loadCalibrationFile, from a parsed camchain YAML tree; `where` prefixes messages.
RectifiedStereoCalibration parseCalibration(const YAML::Node& root, const std::string& where,
                                            bool stereo);

}  // namespace cblox
