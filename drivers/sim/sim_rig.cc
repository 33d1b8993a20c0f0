#include "drivers/sim/sim_rig.h"

#include <cmath>

namespace cblox {

std::string SimRigConfig::validate() const {
  if (std::string problem = cblox::validate(stereo); !problem.empty()) return "stereo: " + problem;
  if (!(baseline_m > 0.0) || !std::isfinite(baseline_m)) {
    return "baseline_m must be > 0, got " + std::to_string(baseline_m);
  }
  if (!(std::abs(right_cx_error_px) <= 10.0)) {
    return "right_cx_error_px must be in [-10, 10] pixels, got " +
           std::to_string(right_cx_error_px);
  }
  if (depth.width != 0) {
    if (std::string problem = cblox::validate(depth); !problem.empty()) return "depth: " + problem;
  }
  if (!T_L_D.translation().allFinite() || !T_L_D.rotation().coeffs().allFinite()) {
    return "T_L_D must be finite";
  }
  if (!(depth_min_m >= 0.0) || !(depth_max_m > depth_min_m) || !std::isfinite(depth_max_m)) {
    return "depth range must satisfy 0 <= depth_min_m < depth_max_m < inf, got [" +
           std::to_string(depth_min_m) + ", " + std::to_string(depth_max_m) + "]";
  }
  return {};
}

PinholeIntrinsics SimRigConfig::depthIntrinsics() const {
  return depth.width == 0 ? stereo : depth;
}

bool SimRigConfig::depthIsLeftCamera() const {
  const PinholeIntrinsics d = depthIntrinsics();
  return d.fx == stereo.fx && d.fy == stereo.fy && d.cx == stereo.cx && d.cy == stereo.cy &&
         d.width == stereo.width && d.height == stereo.height &&
         T_L_D.isApprox(Transformationd::Identity(), 0.0);
}

PinholeIntrinsics SimRigConfig::rightIntrinsics() const {
  PinholeIntrinsics right = stereo;
  right.cx += right_cx_error_px;
  return right;
}

RectifiedStereoCalibration SimRigConfig::stereoCalibration() const {
  RectifiedStereoCalibration calibration;
  calibration.intrinsics = stereo;
  calibration.baseline_m = baseline_m;
  calibration.T_B_L = Transformationd::Identity();
  return calibration;
}

std::string SimLightingConfig::validate() const {
  if (!towards_light_G.allFinite() || !(towards_light_G.norm() > 0.0)) {
    return "towards_light_G must be a finite non-zero vector";
  }
  if (!(ambient >= 0.0) || !(diffuse >= 0.0) || !(ambient + diffuse <= 2.0)) {
    return "ambient and diffuse must be >= 0 with ambient + diffuse <= 2";
  }
  if (background_gray < 0 || background_gray > 255) {
    return "background_gray must be in [0, 255], got " + std::to_string(background_gray);
  }
  return {};
}

}  // namespace cblox
