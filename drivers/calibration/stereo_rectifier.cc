#include "drivers/calibration/stereo_rectifier.h"

#include <cmath>
#include <sstream>
#include <stdexcept>

#include <opencv2/calib3d.hpp>
#include <opencv2/imgproc.hpp>

#include "core/geometry/opencv_view.h"

namespace cblox {
namespace {

cv::Mat cameraMatrix(const PinholeIntrinsics& in) {
  return (cv::Mat_<double>(3, 3) << in.fx, 0, in.cx, 0, in.fy, in.cy, 0, 0, 1);
}

cv::Mat distortionVector(const CameraCalibration& camera) {
  cv::Mat d(1, static_cast<int>(camera.distortion_coefficients.size()), CV_64F);
  for (int k = 0; k < d.cols; ++k) d.at<double>(0, k) = camera.distortion_coefficients[k];
  return d;
}

// Already rectified: undistorted, equal intrinsics, right camera at (+b, 0, 0) unrotated.
bool isRectifiedPair(const StereoCameraCalibration& raw) {
  constexpr double kTolerance = 1e-9;
  return isUndistorted(raw.left) && isUndistorted(raw.right) &&
         rectifiedPairProblem(raw, kTolerance).empty();
}

void checkSize(const cv::Mat& raw, const PinholeIntrinsics& in, const char* camera) {
  if (raw.type() != CV_8UC1 || raw.cols != in.width || raw.rows != in.height) {
    std::ostringstream os;
    os << "StereoRectifier: the " << camera << " image is " << raw.cols << "x" << raw.rows
       << (raw.type() == CV_8UC1 ? "" : " (not 8-bit grey)") << ", the calibration's is "
       << in.width << "x" << in.height;
    throw std::invalid_argument(os.str());
  }
}

}  // namespace

std::shared_ptr<const StereoRectifier> StereoRectifier::create(const StereoCameraCalibration& raw,
                                                               std::string* error) {
  const auto failed = [&](const std::string& message) {
    if (error != nullptr) *error = raw.source + ": " + message;
    return nullptr;
  };
  for (const auto& [name, camera] : {std::pair{"left", &raw.left}, {"right", &raw.right}}) {
    if (const std::string e = validate(*camera); !e.empty()) {
      return failed(std::string(name) + " camera: " + e);
    }
  }
  const PinholeIntrinsics& in0 = raw.left.intrinsics;
  const PinholeIntrinsics& in1 = raw.right.intrinsics;
  if (in0.width != in1.width || in0.height != in1.height) {
    return failed("the right camera's resolution " + std::to_string(in1.width) + "x" +
                  std::to_string(in1.height) + " differs from the left's " +
                  std::to_string(in0.width) + "x" + std::to_string(in0.height));
  }
  std::shared_ptr<StereoRectifier> rectifier(new StereoRectifier());
  rectifier->raw_ = raw;
  const Transformationd T_B_C0 = raw.left.T_B_C.value_or(Transformationd::Identity());
  if (isRectifiedPair(raw)) {
    rectifier->passthrough_ = true;
    rectifier->rectified_.intrinsics = in0;
    rectifier->rectified_.baseline_m = raw.T_R_L.inverse().translation().x();
    rectifier->rectified_.T_B_L = T_B_C0;
    return rectifier;
  }
  const bool fisheye = raw.left.distortion == DistortionModel::kEquidistant;
  if (fisheye != (raw.right.distortion == DistortionModel::kEquidistant)) {
    return failed(std::string("the cameras' distortion models differ (left ") +
                  distortionModelName(raw.left.distortion) + ", right " +
                  distortionModelName(raw.right.distortion) + ")");
  }
  cv::Mat R(3, 3, CV_64F);
  cv::Mat t(3, 1, CV_64F);
  const Eigen::Matrix3d R_R_L = raw.T_R_L.rotationMatrix();
  for (int r = 0; r < 3; ++r) {
    for (int c = 0; c < 3; ++c) R.at<double>(r, c) = R_R_L(r, c);
    t.at<double>(r, 0) = raw.T_R_L.translation()(r);
  }
  const cv::Size size(in0.width, in0.height);
  const cv::Mat K0 = cameraMatrix(in0), K1 = cameraMatrix(in1);
  const cv::Mat D0 = distortionVector(raw.left), D1 = distortionVector(raw.right);
  cv::Mat R1, R2, P1, P2, Q;
  StereoRectifier& s = *rectifier;
  try {
    if (fisheye) {
      cv::fisheye::stereoRectify(K0, D0, K1, D1, size, R, t, R1, R2, P1, P2, Q,
                                 cv::fisheye::CALIB_ZERO_DISPARITY, size, /*balance=*/0.0);
      cv::fisheye::initUndistortRectifyMap(K0, D0, R1, P1, size, CV_16SC2, s.left1_, s.left2_);
      cv::fisheye::initUndistortRectifyMap(K1, D1, R2, P2, size, CV_16SC2, s.right1_,
                                           s.right2_);
    } else {
      cv::stereoRectify(K0, D0, K1, D1, size, R, t, R1, R2, P1, P2, Q, cv::CALIB_ZERO_DISPARITY,
                        /*alpha=*/0.0, size);
      cv::initUndistortRectifyMap(K0, D0, R1, P1, size, CV_16SC2, s.left1_, s.left2_);
      cv::initUndistortRectifyMap(K1, D1, R2, P2, size, CV_16SC2, s.right1_, s.right2_);
    }
  } catch (const cv::Exception& e) {
    return failed(std::string("stereo rectification failed: ") + e.what());
  }
  P1.convertTo(P1, CV_64F);
  P2.convertTo(P2, CV_64F);
  R1.convertTo(R1, CV_64F);
  PinholeIntrinsics& rectified = s.rectified_.intrinsics;
  rectified = PinholeIntrinsics{P1.at<double>(0, 0), P1.at<double>(1, 1), P1.at<double>(0, 2),
                                P1.at<double>(1, 2), in0.width, in0.height};
  if (const std::string invalid = validate(rectified); !invalid.empty()) {
    return failed("stereo rectification gave invalid intrinsics: " + invalid);
  }
  const double fx_tx = P2.at<double>(0, 3);  // = -fx * baseline for the right camera at +x
  if (std::abs(P2.at<double>(1, 3)) > std::abs(fx_tx)) {
    return failed("the right camera is displaced vertically from the left one; only "
                  "horizontal stereo is supported");
  }
  if (!(fx_tx < 0)) {
    std::ostringstream os;
    os << "the right camera must be to the right (+x) of the left one after rectification, "
       << "but P2(0,3) = " << fx_tx << " (cameras swapped? left camera in the right one at "
       << raw.T_R_L.translation().transpose() << " m)";
    return failed(os.str());
  }
  s.rectified_.baseline_m = -fx_tx / P2.at<double>(0, 0);
  Eigen::Matrix3d R_L_C0;
  for (int r = 0; r < 3; ++r) {
    for (int c = 0; c < 3; ++c) R_L_C0(r, c) = R1.at<double>(r, c);
  }
  s.rectified_.T_B_L =
      T_B_C0 * Transformationd(Eigen::Matrix3d(R_L_C0.transpose()), Eigen::Vector3d::Zero());
  return rectifier;
}

void StereoRectifier::rectifyImage(bool right, const cv::Mat& raw, cv::Mat* rectified) const {
  checkSize(raw, right ? raw_.right.intrinsics : raw_.left.intrinsics, right ? "right" : "left");
  if (passthrough_) {
    raw.copyTo(*rectified);
    return;
  }
  cv::remap(raw, *rectified, right ? right1_ : left1_, right ? right2_ : left2_,
            cv::INTER_LINEAR, cv::BORDER_REPLICATE);
}

void StereoRectifier::rectify(const GrayImage& left_raw, const GrayImage& right_raw,
                              GrayImage* left, GrayImage* right) const {
  const int w = rectified_.intrinsics.width, h = rectified_.intrinsics.height;
  for (const auto& [is_right, raw, out] :
       {std::tuple{false, &left_raw, left}, std::tuple{true, &right_raw, right}}) {
    GrayImage result(w, h);
    cv::Mat mat = cvView(&result);
    rectifyImage(is_right, cvView(*raw), &mat);
    if (mat.data != result.data.data()) throw std::logic_error("rectify: reallocated output");
    *out = std::move(result);
  }
}

}  // namespace cblox
