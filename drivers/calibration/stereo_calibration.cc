#include "drivers/calibration/stereo_calibration.h"

#include <algorithm>
#include <cmath>
#include <sstream>

namespace cblox {

const char* distortionModelName(DistortionModel model) {
  switch (model) {
    case DistortionModel::kNone:
      return "none";
    case DistortionModel::kRadTan:
      return "radtan";
    case DistortionModel::kEquidistant:
      return "equidistant";
  }
  return "?";
}

std::string validate(const CameraCalibration& camera) {
  if (std::string e = validate(camera.intrinsics); !e.empty()) return "intrinsics: " + e;
  const std::vector<double>& d = camera.distortion_coefficients;
  for (const double c : d) {
    if (!std::isfinite(c)) return "distortion coefficients must be finite";
  }
  const size_t n = d.size();
  switch (camera.distortion) {
    case DistortionModel::kNone:
      if (!isUndistorted(camera)) return "distortion model none with non-zero coefficients";
      break;
    case DistortionModel::kRadTan:
      if (n != 4 && n != 5 && n != 8 && n != 12 && n != 14) {
        return "radtan needs 4, 5, 8, 12 or 14 coefficients (k1 k2 p1 p2 [k3 ...]), got " +
               std::to_string(n);
      }
      break;
    case DistortionModel::kEquidistant:
      if (n != 4) {
        return "equidistant needs 4 coefficients (k1 k2 k3 k4), got " + std::to_string(n);
      }
      break;
  }
  return {};
}

bool isUndistorted(const CameraCalibration& camera) {
  return std::all_of(camera.distortion_coefficients.begin(), camera.distortion_coefficients.end(),
                     [](double c) { return c == 0.0; });
}

bool sameIntrinsics(const PinholeIntrinsics& a, const PinholeIntrinsics& b, double tolerance) {
  return a.width == b.width && a.height == b.height && std::abs(a.fx - b.fx) <= tolerance &&
         std::abs(a.fy - b.fy) <= tolerance && std::abs(a.cx - b.cx) <= tolerance &&
         std::abs(a.cy - b.cy) <= tolerance;
}

std::string rectifiedPairProblem(const StereoCameraCalibration& pair, double tolerance) {
  if (!sameIntrinsics(pair.left.intrinsics, pair.right.intrinsics, tolerance)) {
    return "intrinsics and resolution must equal the left camera's (a rectified pair)";
  }
  const Transformationd T_L_R = pair.T_R_L.inverse();
  const Eigen::Vector3d& t = T_L_R.translation();
  const double angle = T_L_R.rotation().angularDistance(Eigen::Quaterniond::Identity());
  if (angle <= tolerance && std::abs(t.y()) <= tolerance && std::abs(t.z()) <= tolerance &&
      t.x() > 0.0) {
    return {};
  }
  std::ostringstream os;
  os << "the right camera must sit at (+baseline, 0, 0) in the left one without rotation (a "
     << "rectified pair); it is at (" << t.x() << ", " << t.y() << ", " << t.z()
     << ") m, rotated by " << angle << " rad";
  return os.str();
}

}  // namespace cblox
