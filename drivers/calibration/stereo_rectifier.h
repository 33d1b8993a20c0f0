#pragma once

#include <memory>
#include <string>

#include <opencv2/core.hpp>

#include "core/geometry/image.h"
#include "core/geometry/stereo_rig.h"
#include "drivers/calibration/stereo_calibration.h"

namespace cblox {

/// Rectifies the images of a raw stereo pair so that epipolar lines are image rows.
///
/// The maps are built once, in create(): cv::stereoRectify (cv::fisheye::stereoRectify for
/// the equidistant model) with zero disparity at infinity and alpha = 0 (every rectified pixel
/// sees the scene, no black borders), at the raw image size, and cv::initUndistortRectifyMap
/// in fixed point (CV_16SC2). rectify() is then one cv::remap per image, bilinear, with the
/// border replicated (OpenCV's inner rectangle lets a few edge pixels land up to ~0.1 px
/// outside the raw image).
///
/// A calibration that is already rectified (no distortion, equal intrinsics, the right camera
/// at (+b, 0, 0) in the left one without rotation, within 1e-9) is passed through unchanged:
/// rectify() copies and rectified() has the raw intrinsics exactly.
///
/// Immutable after create(): every member function is thread-safe.
class StereoRectifier {
 public:
  /// Builds the rectification of `raw`. Returns nullptr and a message (starting with
  /// raw.source) when a camera is invalid, the two resolutions differ, the cameras do not
  /// share one distortion model, OpenCV fails, the rectified intrinsics are invalid, the
  /// right camera is displaced mostly vertically (only horizontal rigs are supported) or sits
  /// to the left of the left camera (cameras swapped). Thread-safe.
  static std::shared_ptr<const StereoRectifier> create(const StereoCameraCalibration& raw,
                                                       std::string* error);

  /// The calibration of the rectified pair: shared intrinsics (from P1), baseline (from P2)
  /// and T_B_L = T_B_C0 * R1^T (the rectified left camera in the body frame; identity body
  /// frame when the file gives none). Thread-safe.
  const RectifiedStereoCalibration& rectified() const { return rectified_; }

  /// The raw calibration it was built from. Thread-safe.
  const StereoCameraCalibration& raw() const { return raw_; }

  /// True when create() found the pair already rectified and rectify() only copies.
  bool passthrough() const { return passthrough_; }

  /// Rectifies a raw pair into *left, *right (resized to the rectified size). Throws
  /// std::invalid_argument naming the camera when an image's size is not the calibrated
  /// resolution. Thread-safe.
  void rectify(const GrayImage& left_raw, const GrayImage& right_raw, GrayImage* left,
               GrayImage* right) const;

  /// Rectifies one raw 8-bit grey image of the left (right = false) or right camera into
  /// *rectified. Throws std::invalid_argument on a size or type mismatch. Thread-safe.
  void rectifyImage(bool right, const cv::Mat& raw, cv::Mat* rectified) const;

 private:
  StereoRectifier() = default;

  StereoCameraCalibration raw_;
  RectifiedStereoCalibration rectified_;
  bool passthrough_ = false;
  cv::Mat left1_, left2_, right1_, right2_;
};

}  // namespace cblox
