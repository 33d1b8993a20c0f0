#include "daemon/tracker/calibration_file.h"

#include "daemon/common/yaml_config.h"
#include "drivers/calibration/calibration_file.h"

namespace cblox {
namespace {

void requireUndistorted(const CameraCalibration& camera) {
  if (!isUndistorted(camera)) {
    throw ConfigError(camera.distortion_key +
                      ": must be all 0 (the tracker takes rectified, undistorted images; "
                      "rectify in the capture)");
  }
}

// The rectified pair the file describes, or ConfigError when it is not one.
RectifiedStereoCalibration requireRectified(const StereoCameraCalibration& file,
                                            const std::string& where, bool stereo) {
  requireUndistorted(file.left);
  RectifiedStereoCalibration calibration;
  calibration.intrinsics = file.left.intrinsics;
  calibration.T_B_L = file.left.T_B_C.value_or(Transformationd::Identity());
  if (!stereo) return calibration;
  const std::string key = where + ".cam1";
  requireUndistorted(file.right);
  constexpr double kTolerance = 1e-6;
  if (const std::string problem = rectifiedPairProblem(file, kTolerance); !problem.empty()) {
    throw ConfigError(key + ": " + problem);
  }
  calibration.baseline_m = file.T_R_L.inverse().translation().x();
  return calibration;
}

}  // namespace

RectifiedStereoCalibration parseCalibration(const YAML::Node& root, const std::string& where,
                                            bool stereo) {
  try {
    return requireRectified(parseCamchain(root, where, stereo), where, stereo);
  } catch (const CalibrationError& e) {
    throw ConfigError(e.what());
  }
}

RectifiedStereoCalibration loadCalibrationFile(const std::string& path, bool stereo) {
  try {
    return requireRectified(loadStereoCalibration(path, stereo), path, stereo);
  } catch (const CalibrationError& e) {
    throw ConfigError(e.what());
  }
}

}  // namespace cblox
