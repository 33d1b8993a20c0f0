#include "drivers/stereo_depth/stereo_depth.h"

#include <cmath>
#include <stdexcept>

#include <opencv2/calib3d.hpp>
#include <opencv2/imgproc.hpp>

#include "core/geometry/opencv_view.h"

namespace cblox {

struct StereoDepthEstimator::Impl {
  cv::Ptr<cv::StereoMatcher> matcher;
  cv::Mat left_small, right_small, disparity;
};

const char* stereoMatcherName(StereoMatcherType type) {
  switch (type) {
    case StereoMatcherType::kSgbm:
      return "sgbm";
    case StereoMatcherType::kSgbm3Way:
      return "sgbm3way";
    case StereoMatcherType::kBlockMatching:
      return "bm";
  }
  return "?";
}

bool parseStereoMatcher(const std::string& name, StereoMatcherType* type) {
  for (StereoMatcherType t : {StereoMatcherType::kSgbm, StereoMatcherType::kSgbm3Way,
                              StereoMatcherType::kBlockMatching}) {
    if (name == stereoMatcherName(t)) {
      *type = t;
      return true;
    }
  }
  return false;
}

std::string StereoDepthConfig::validate() const {
  if (downscale < 1 || downscale > 8) {
    return "downscale must be 1..8, got " + std::to_string(downscale);
  }
  if (num_disparities < 16 || num_disparities % 16 != 0 || num_disparities > 1024) {
    return "num_disparities must be a positive multiple of 16 (<= 1024), got " +
           std::to_string(num_disparities);
  }
  const bool bm = matcher == StereoMatcherType::kBlockMatching;
  const int min_block = bm ? 5 : 1, max_block = bm ? 255 : 21;
  if (block_size % 2 == 0 || block_size < min_block || block_size > max_block) {
    return "block_size must be odd, " + std::to_string(min_block) + ".." +
           std::to_string(max_block) + " for " + stereoMatcherName(matcher) + ", got " +
           std::to_string(block_size);
  }
  if (uniqueness_ratio < 0 || uniqueness_ratio > 100) {
    return "uniqueness_ratio must be 0..100, got " + std::to_string(uniqueness_ratio);
  }
  if (speckle_window < 0 || speckle_range < 0) {
    return "speckle_window and speckle_range must be >= 0";
  }
  if (texture_threshold < 0) return "texture_threshold must be >= 0";
  if (!(min_depth_m > 0) || !(max_depth_m > min_depth_m) || !std::isfinite(max_depth_m)) {
    return "depth range must satisfy 0 < min_depth_m < max_depth_m < inf";
  }
  return {};
}

StereoDepthEstimator::~StereoDepthEstimator() = default;

std::unique_ptr<StereoDepthEstimator> StereoDepthEstimator::create(
    const RectifiedStereoCalibration& calibration, const StereoDepthConfig& config,
    std::string* error) {
  const auto failed = [&](const std::string& message) {
    if (error != nullptr) *error = "stereo depth: " + message;
    return nullptr;
  };
  if (const std::string e = config.validate(); !e.empty()) return failed(e);
  if (const std::string e = validate(calibration.intrinsics); !e.empty()) return failed(e);
  if (!(calibration.baseline_m > 0) || !std::isfinite(calibration.baseline_m)) {
    return failed("the stereo baseline must be > 0, got " + std::to_string(calibration.baseline_m));
  }
  const PinholeIntrinsics& in = calibration.intrinsics;
  const double s = config.downscale;
  PinholeIntrinsics working{in.fx / s, in.fy / s, (in.cx + 0.5) / s - 0.5, (in.cy + 0.5) / s - 0.5,
                            in.width / config.downscale, in.height / config.downscale};
  if (working.width <= config.num_disparities + config.block_size || working.height < 1) {
    return failed("the working image (" + std::to_string(working.width) + "x" +
                  std::to_string(working.height) + ") must be wider than num_disparities + " +
                  "block_size (" + std::to_string(config.num_disparities + config.block_size) +
                  ")");
  }
  std::unique_ptr<StereoDepthEstimator> estimator(new StereoDepthEstimator());
  estimator->calibration_ = calibration;
  estimator->config_ = config;
  estimator->depth_intrinsics_ = working;
  estimator->impl_ = std::make_unique<Impl>();
  const int lr = config.left_right_max_diff;  // OpenCV: < 0 disables the check
  if (config.matcher == StereoMatcherType::kBlockMatching) {
    cv::Ptr<cv::StereoBM> bm = cv::StereoBM::create(config.num_disparities, config.block_size);
    bm->setUniquenessRatio(config.uniqueness_ratio);
    bm->setDisp12MaxDiff(lr);
    bm->setSpeckleWindowSize(config.speckle_window);
    bm->setSpeckleRange(config.speckle_range);
    bm->setTextureThreshold(config.texture_threshold);
    bm->setPreFilterCap(31);
    estimator->impl_->matcher = bm;
  } else {
    // OpenCV's recommended smoothness penalties for one channel.
    const int area = config.block_size * config.block_size;
    estimator->impl_->matcher = cv::StereoSGBM::create(
        0, config.num_disparities, config.block_size, 8 * area, 32 * area, lr,
        /*preFilterCap=*/63, config.uniqueness_ratio, config.speckle_window, config.speckle_range,
        config.matcher == StereoMatcherType::kSgbm3Way ? cv::StereoSGBM::MODE_SGBM_3WAY
                                                       : cv::StereoSGBM::MODE_SGBM);
  }
  return estimator;
}

StereoDepthStats StereoDepthEstimator::compute(const GrayImage& left, const GrayImage& right,
                                               DepthImage* depth) {
  const PinholeIntrinsics& in = calibration_.intrinsics;
  for (const GrayImage* image : {&left, &right}) {
    if (image->width != in.width || image->height != in.height ||
        image->data.size() != static_cast<size_t>(in.width) * static_cast<size_t>(in.height)) {
      throw std::invalid_argument(
          "stereo depth: image " + std::to_string(image->width) + "x" +
          std::to_string(image->height) + " is not the calibration's " + std::to_string(in.width) +
          "x" + std::to_string(in.height));
    }
  }
  Impl& impl = *impl_;
  const cv::Mat l = cvView(left), r = cvView(right);
  const PinholeIntrinsics& out = depth_intrinsics_;
  if (config_.downscale > 1) {
    // Crop to a multiple of the factor first, so that INTER_AREA averages whole blocks.
    const cv::Rect whole(0, 0, out.width * config_.downscale, out.height * config_.downscale);
    cv::resize(l(whole), impl.left_small, cv::Size(out.width, out.height), 0, 0, cv::INTER_AREA);
    cv::resize(r(whole), impl.right_small, cv::Size(out.width, out.height), 0, 0,
               cv::INTER_AREA);
  } else {
    impl.left_small = l;
    impl.right_small = r;
  }
  impl.matcher->compute(impl.left_small, impl.right_small, impl.disparity);  // CV_16S, 1/16 px

  *depth = DepthImage(out.width, out.height, 0.0f);
  const double fx_b = out.fx * calibration_.baseline_m;
  StereoDepthStats stats;
  stats.total_pixels = out.width * out.height;
  for (int v = 0; v < out.height; ++v) {
    const int16_t* row = impl.disparity.ptr<int16_t>(v);
    for (int u = 0; u < out.width; ++u) {
      if (row[u] <= 0) continue;  // invalid (OpenCV marks them (minDisparity - 1) * 16)
      const double z = fx_b * 16.0 / row[u];
      if (z < config_.min_depth_m || z > config_.max_depth_m) continue;
      (*depth)(u, v) = static_cast<float>(z);
      ++stats.valid_pixels;
    }
  }
  return stats;
}

}  // namespace cblox
