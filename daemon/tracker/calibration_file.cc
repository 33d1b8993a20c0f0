#include "daemon/tracker/calibration_file.h"

#include <cmath>
#include <sstream>

#include "daemon/common/yaml_config.h"
#include "drivers/calibration/calibration_file.h"

namespace cblox {
namespace {

bool sameIntrinsics(const PinholeIntrinsics& a, const PinholeIntrinsics& b) {
  constexpr double kTolerance = 1e-6;
  return a.width == b.width && a.height == b.height && std::abs(a.fx - b.fx) <= kTolerance &&
         std::abs(a.fy - b.fy) <= kTolerance && std::abs(a.cx - b.cx) <= kTolerance &&
         std::abs(a.cy - b.cy) <= kTolerance;
}

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
  if (!sameIntrinsics(file.left.intrinsics, file.right.intrinsics)) {
    throw ConfigError(key + ": intrinsics and resolution must equal cam0's (a rectified pair)");
  }
  const Transformationd T_L_R = file.T_R_L.inverse();
  const Eigen::Vector3d& t = T_L_R.translation();
  constexpr double kTolerance = 1e-6;
  const double angle = T_L_R.rotation().angularDistance(Eigen::Quaterniond::Identity());
  if (angle > kTolerance || std::abs(t.y()) > kTolerance || std::abs(t.z()) > kTolerance ||
      !(t.x() > 0.0)) {
    std::ostringstream os;
    os << key << ": the right camera must sit at (+baseline, 0, 0) in the left one without "
       << "rotation (a rectified pair); it is at (" << t.x() << ", " << t.y() << ", " << t.z()
       << ") m, rotated by " << angle << " rad";
    throw ConfigError(os.str());
  }
  calibration.baseline_m = t.x();
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
