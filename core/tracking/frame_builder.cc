#include "core/tracking/frame_builder.h"

#include <sstream>
#include <stdexcept>
#include <utility>

#include "core/common/thread_name.h"
#include "core/features/rgbd_depth.h"

namespace cblox {

std::string FrameBuilderConfig::validate() const {
  if (std::string e = orb.validate(); !e.empty()) return "orb: " + e;
  if (std::string e = stereo.validate(); !e.empty()) return "stereo: " + e;
  if (grid_cols < 1 || grid_rows < 1) {
    std::ostringstream error;
    error << "grid_cols and grid_rows must be >= 1, got " << grid_cols << " x " << grid_rows;
    return error.str();
  }
  return "";
}

FrameBuilder::FrameBuilder(const TrackingCamera& camera, const FrameBuilderConfig& config,
                           const BinaryVocabulary* vocabulary)
    : camera_(camera),
      config_(config),
      vocabulary_(vocabulary),
      left_(config.orb),
      right_(config.orb) {
  if (std::string e = camera.validate(); !e.empty()) {
    throw std::invalid_argument("FrameBuilder: camera: " + e);
  }
  if (std::string e = config.validate(); !e.empty()) {
    throw std::invalid_argument("FrameBuilder: " + e);
  }
  if (config_.parallel_stereo_extraction)
    worker_ = std::thread([this] {
      nameThisThread("cblox-extract");
      rightWorker();
    });
}

FrameBuilder::~FrameBuilder() {
  {
    std::lock_guard<std::mutex> lock(mutex_);
    stop_ = true;
  }
  cv_.notify_all();
  if (worker_.joinable()) worker_.join();
}

void FrameBuilder::rightWorker() {
  std::unique_lock<std::mutex> lock(mutex_);
  while (true) {
    cv_.wait(lock, [this] { return stop_ || right_job_ != nullptr; });
    if (stop_) return;
    const GrayImage* image = right_job_;
    lock.unlock();
    ExtractedFeatures result;
    std::string error;
    try {
      result = right_.extract(*image);
    } catch (const std::exception& e) {
      error = e.what();
    }
    lock.lock();
    right_result_ = std::move(result);
    right_error_ = std::move(error);
    right_job_ = nullptr;
    right_done_ = true;
    cv_.notify_all();
  }
}

void FrameBuilder::checkSize(int width, int height, const char* what) const {
  if (width != camera_.intrinsics.width || height != camera_.intrinsics.height) {
    std::ostringstream error;
    error << what << " is " << width << "x" << height << ", the camera's images are "
          << camera_.intrinsics.width << "x" << camera_.intrinsics.height;
    throw std::invalid_argument(error.str());
  }
}

std::shared_ptr<FrameFeatures> FrameBuilder::fromStereo(const GrayImage& left,
                                                        const GrayImage& right,
                                                        float disparity_correction_px) {
  checkSize(left.width, left.height, "left image");
  checkSize(right.width, right.height, "right image");
  ExtractedFeatures left_features, right_features;
  if (worker_.joinable()) {
    {
      std::lock_guard<std::mutex> lock(mutex_);
      right_job_ = &right;
      right_done_ = false;
    }
    cv_.notify_all();
    std::string left_error;
    try {
      left_features = left_.extract(left);
    } catch (const std::exception& e) {
      left_error = e.what();
    }
    std::unique_lock<std::mutex> lock(mutex_);
    cv_.wait(lock, [this] { return right_done_; });
    right_features = std::move(right_result_);
    if (!left_error.empty()) throw std::invalid_argument("left image: " + left_error);
    if (!right_error_.empty()) throw std::invalid_argument("right image: " + right_error_);
  } else {
    left_features = left_.extract(left);
    right_features = right_.extract(right);
  }
  StereoDepth depth = matchStereo(left_features, right_features, camera_.intrinsics.fx,
                                  camera_.baseline_m, config_.stereo);
  if (disparity_correction_px != 0.0f) {
    const float bf = static_cast<float>(camera_.bf());
    for (size_t i = 0; i < depth.right_u.size(); ++i) {
      if (depth.right_u[i] < 0.0f) continue;
      const float right_u = depth.right_u[i] - disparity_correction_px;
      const float disparity = left_features.keypoints[i].u - right_u;
      if (right_u >= 0.0f && disparity > 0.0f) {
        depth.right_u[i] = right_u;
        depth.depth[i] = bf / disparity;
      } else {
        depth.right_u[i] = -1.0f;
        depth.depth[i] = -1.0f;
      }
    }
  }
  std::shared_ptr<FrameFeatures> f = finish(std::move(left_features), depth);
  f->disparity_correction_px = disparity_correction_px;
  f->stereo_matched = true;
  return f;
}

std::shared_ptr<FrameFeatures> FrameBuilder::fromRgbd(const GrayImage& gray,
                                                      const DepthImage& depth) {
  checkSize(gray.width, gray.height, "grey image");
  checkSize(depth.width, depth.height, "depth image");
  ExtractedFeatures features = left_.extract(gray);
  const StereoDepth stereo = depthFromRgbd(features.keypoints, depth, camera_.bf());
  return finish(std::move(features), stereo);
}

std::shared_ptr<FrameFeatures> FrameBuilder::finish(ExtractedFeatures&& extracted,
                                                    const StereoDepth& depth) {
  auto f = std::make_shared<FrameFeatures>();
  f->keypoints = std::move(extracted.keypoints);
  f->descriptors = std::move(extracted.descriptors);
  f->right_u = depth.right_u;
  f->depth = depth.depth;
  buildGrid(f.get());
  return f;
}

void FrameBuilder::buildGrid(FrameFeatures* f) const {
  f->grid = FeatureGrid(f->keypoints, camera_.intrinsics.width, camera_.intrinsics.height,
                        config_.grid_cols, config_.grid_rows);
}

void FrameBuilder::index(FrameFeatures* f) const {
  buildGrid(f);
  if (vocabulary_ != nullptr) vocabulary_->transform(f->descriptors, &f->bow, &f->feature_vector);
}

}  // namespace cblox
