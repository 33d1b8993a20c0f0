#pragma once

#include <condition_variable>
#include <memory>
#include <mutex>
#include <string>
#include <thread>

#include "core/features/orb_extractor.h"
#include "core/features/stereo_matcher.h"
#include "core/geometry/image.h"
#include "core/tracking/frame_features.h"
#include "core/tracking/tracking_camera.h"
#include "core/vocabulary/binary_vocabulary.h"

namespace cblox {

/// Settings of turning images into FrameFeatures.
struct FrameBuilderConfig {
  OrbExtractorConfig orb;
  StereoMatcherConfig stereo;
  /// Extract the right image on a second thread while the calling thread extracts the left
  /// (ORB-SLAM2 does the same); false: both on the calling thread.
  bool parallel_stereo_extraction = true;
  /// Cells of the feature grid (ORB-SLAM2: 64 x 48).
  int grid_cols = 64, grid_rows = 48;
  std::string validate() const;
};

/// Builds the features of a frame: ORB features of the left image, their depth from stereo
/// matching against the right image (or from a registered depth image, RGB-D mode) and the
/// feature grid. The BoW vectors are left empty: the Tracker computes them when it needs
/// them (most frames never do); `index` computes them for features restored from a file.
/// Thread-safety: not thread-safe (one tracking thread calls it); it owns the worker thread
/// that extracts right images.
class FrameBuilder {
 public:
  /// Throws std::invalid_argument for an invalid config or camera. `vocabulary` (for
  /// `index`) may be null (then bow / feature_vector stay empty) and must outlive the builder.
  FrameBuilder(const TrackingCamera& camera, const FrameBuilderConfig& config,
               const BinaryVocabulary* vocabulary);
  ~FrameBuilder();
  FrameBuilder(const FrameBuilder&) = delete;
  FrameBuilder& operator=(const FrameBuilder&) = delete;

  /// A rectified stereo pair of the camera's size. Every matched right column is corrected
  /// by `disparity_correction_px` (see FrameFeatures::disparity_correction_px); a match whose
  /// corrected disparity is not > 0 loses its depth. Throws std::invalid_argument when an
  /// image's size differs from the camera's.
  std::shared_ptr<FrameFeatures> fromStereo(const GrayImage& left, const GrayImage& right,
                                            float disparity_correction_px = 0.0f);
  /// A grey image and a depth image registered to it (metres), both of the camera's size.
  std::shared_ptr<FrameFeatures> fromRgbd(const GrayImage& gray, const DepthImage& depth);

  /// Builds the feature grid of `features` (keypoints in this camera's image) and, with a
  /// vocabulary, its BoW vectors: what fromStereo / fromRgbd add to the extracted features,
  /// for features restored from a file. Thread-safe (const; the vocabulary is read-only).
  void index(FrameFeatures* features) const;

  const ScalePyramid& pyramid() const { return left_.scales(); }

 private:
  std::shared_ptr<FrameFeatures> finish(ExtractedFeatures&& left, const StereoDepth& depth);
  void checkSize(int width, int height, const char* what) const;
  void buildGrid(FrameFeatures* features) const;
  void rightWorker();

  TrackingCamera camera_;
  FrameBuilderConfig config_;
  const BinaryVocabulary* vocabulary_;
  OrbExtractor left_, right_;
  // Right-image job for the worker thread.
  std::mutex mutex_;
  std::condition_variable cv_;
  const GrayImage* right_job_ = nullptr;
  ExtractedFeatures right_result_;
  std::string right_error_;
  bool right_done_ = false, stop_ = false;
  std::thread worker_;
};

}  // namespace cblox
