#include "drivers/stereo_depth/stereo_depth.h"

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <vector>
#include <random>
#include <string>

#include <gtest/gtest.h>

#include "core/features/orb_extractor.h"
#include "core/features/stereo_matcher.h"
#include "drivers/open_frame_source.h"
#include "drivers/stereo_depth/depth_accuracy.h"

namespace cblox {
namespace {

RectifiedStereoCalibration rig(int width, int height) {
  RectifiedStereoCalibration calibration;
  calibration.intrinsics = {400.0, 400.0, (width - 1) / 2.0, (height - 1) / 2.0, width, height};
  calibration.baseline_m = 0.1;
  return calibration;
}

// Random texture, and the same texture moved `shift` pixels left: the right image of a
// fronto-parallel plane at disparity `shift`.
void shiftedPair(int width, int height, int shift, GrayImage* left, GrayImage* right) {
  std::mt19937 random(7);
  std::uniform_int_distribution<int> grey(0, 255);
  GrayImage cells(width + shift, height);
  for (uint8_t& c : cells.data) c = static_cast<uint8_t>(grey(random));
  *left = GrayImage(width, height);
  *right = GrayImage(width, height);
  for (int v = 0; v < height; ++v) {
    for (int u = 0; u < width; ++u) {
      (*left)(u, v) = cells(u, v);
      (*right)(u, v) = cells(u + shift, v);  // x_right = x_left - disparity
    }
  }
}

TEST(StereoDepthTest, PlaneAtKnownDisparityGivesExactDepth) {
  GrayImage left, right;
  shiftedPair(320, 240, 20, &left, &right);
  for (StereoMatcherType matcher : {StereoMatcherType::kSgbm, StereoMatcherType::kSgbm3Way,
                                    StereoMatcherType::kBlockMatching}) {
    StereoDepthConfig config;
    config.matcher = matcher;
    config.downscale = 1;
    config.block_size = matcher == StereoMatcherType::kBlockMatching ? 9 : 5;
    std::string error;
    auto estimator = StereoDepthEstimator::create(rig(320, 240), config, &error);
    ASSERT_NE(estimator, nullptr) << error;
    DepthImage depth;
    const StereoDepthStats stats = estimator->compute(left, right, &depth);
    ASSERT_EQ(depth.width, 320);
    const float z = static_cast<float>(400.0 * 0.1 / 20.0);  // 2 m
    // Within OpenCV's sub-pixel step: disparity 20 +- 1/16 px.
    const float step = z * (1.0f / 16.0f) / 20.0f;
    int exact = 0, checked = 0;
    for (int v = 10; v < 230; ++v) {
      for (int u = 64 + 20 + 10; u < 310; ++u) {  // right of the search band and the shift
        ++checked;
        exact += std::abs(depth(u, v) - z) <= step;
      }
    }
    EXPECT_GT(exact, 0.95 * checked) << stereoMatcherName(matcher);
    // Nothing outside the plane: every valid pixel is at 2 m.
    int wrong = 0;
    for (float d : depth.data) wrong += d > 0.0f && std::abs(d - z) > 0.05f;
    EXPECT_LT(wrong, 0.01 * stats.total_pixels) << stereoMatcherName(matcher);
    EXPECT_EQ(stats.total_pixels, 320 * 240);
  }
}

TEST(StereoDepthTest, TexturelessImagesGiveNoDepth) {
  StereoDepthConfig config;
  config.matcher = StereoMatcherType::kBlockMatching;
  config.block_size = 9;
  config.downscale = 1;
  std::string error;
  auto estimator = StereoDepthEstimator::create(rig(160, 120), config, &error);
  ASSERT_NE(estimator, nullptr) << error;
  DepthImage depth;
  const GrayImage flat(160, 120, 128);
  EXPECT_EQ(estimator->compute(flat, flat, &depth).valid_pixels, 0);
}

TEST(StereoDepthTest, DownscaledIntrinsicsAndRange) {
  StereoDepthConfig config;
  config.downscale = 2;
  config.min_depth_m = 2.5;  // the plane at 2 m is out of range
  std::string error;
  auto estimator = StereoDepthEstimator::create(rig(320, 240), config, &error);
  ASSERT_NE(estimator, nullptr) << error;
  const PinholeIntrinsics& K = estimator->depthIntrinsics();
  EXPECT_EQ(K.width, 160);
  EXPECT_EQ(K.height, 120);
  EXPECT_EQ(K.fx, 200.0);
  EXPECT_EQ(K.cx, (159.5 + 0.5) / 2 - 0.5);
  GrayImage left, right;
  shiftedPair(320, 240, 40, &left, &right);
  DepthImage depth;
  EXPECT_EQ(estimator->compute(left, right, &depth).valid_pixels, 0);
}

TEST(StereoDepthTest, RefusesBadConfigAndImages) {
  struct Case {
    void (*edit)(StereoDepthConfig*);
    const char* message;
  };
  const Case cases[] = {
      {[](StereoDepthConfig* c) { c->num_disparities = 40; }, "num_disparities"},
      {[](StereoDepthConfig* c) { c->block_size = 4; }, "block_size"},
      {[](StereoDepthConfig* c) { c->downscale = 0; }, "downscale"},
      {[](StereoDepthConfig* c) { c->uniqueness_ratio = -1; }, "uniqueness_ratio"},
      {[](StereoDepthConfig* c) { c->max_depth_m = 0.1; }, "depth range"},
      {[](StereoDepthConfig* c) { c->num_disparities = 512; }, "wider than"},
      {[](StereoDepthConfig* c) {
         c->matcher = StereoMatcherType::kBlockMatching;
         c->block_size = 3;
       },
       "5..255"},
  };
  for (const Case& c : cases) {
    StereoDepthConfig config;
    c.edit(&config);
    std::string error;
    EXPECT_EQ(StereoDepthEstimator::create(rig(752, 480), config, &error), nullptr) << c.message;
    EXPECT_NE(error.find(c.message), std::string::npos) << error;
  }
  RectifiedStereoCalibration mono = rig(752, 480);
  mono.baseline_m = 0.0;
  std::string error;
  EXPECT_EQ(StereoDepthEstimator::create(mono, StereoDepthConfig{}, &error), nullptr);
  EXPECT_NE(error.find("baseline"), std::string::npos) << error;
  auto estimator = StereoDepthEstimator::create(rig(752, 480), StereoDepthConfig{}, &error);
  ASSERT_NE(estimator, nullptr) << error;
  DepthImage depth;
  EXPECT_THROW(estimator->compute(GrayImage(752, 480), GrayImage(640, 480), &depth),
               std::invalid_argument);
  StereoMatcherType type;
  EXPECT_TRUE(parseStereoMatcher("bm", &type));
  EXPECT_EQ(type, StereoMatcherType::kBlockMatching);
  EXPECT_FALSE(parseStereoMatcher("census", &type));
}

// The simulator's exact depth: SGBM at half resolution on rendered room pairs.
TEST(StereoDepthTest, SimulatedRoomAgainstExactDepth) {
  SourceConfig options;
  options.max_frames = 3;
  std::string error;
  auto source = openFrameSource("sim:room", options, &error);
  ASSERT_NE(source, nullptr) << error;
  auto estimator = StereoDepthEstimator::create(*source->info().stereo, StereoDepthConfig{}, &error);
  ASSERT_NE(estimator, nullptr) << error;
  CaptureFrame frame;
  while (source->next(&frame, &error) == FrameSource::Status::kFrame) {
    DepthImage depth;
    estimator->compute(frame.left, frame.right, &depth);
    const DepthAccuracy a = compareToExactDepth(depth, 2, frame.depth);
    RecordProperty("median_rel_" + std::to_string(frame.frame_id), std::to_string(a.median_rel));
    EXPECT_GT(a.completeness, 0.6) << frame.frame_id;
    EXPECT_LT(a.median_rel, 0.015) << frame.frame_id;  // 1.1 % measured (0.75 % at full size)
    EXPECT_LT(a.outlier_fraction, 0.05) << frame.frame_id;
  }
}

// Real street stereo at KITTI's 0.54 m baseline: the dense depth agrees with the sparse
// stereo depths the tracker computes (ORB keypoints matched along the rows) where both have
// one, on three frames of the shared clip.
TEST(StereoDepthTest, KittiDenseDepthAgreesWithTheSparseStereoDepths) {
  const std::string clip = std::string(CBLOX_SHARED_DATA_DIR) + "/kitti-odometry-51";
  if (!std::filesystem::is_directory(clip)) GTEST_SKIP() << "shared data not present at " << clip;
  std::string error;
  auto source = openFrameSource("kitti:" + clip, SourceConfig{}, &error);
  ASSERT_NE(source, nullptr) << error;
  const RectifiedStereoCalibration& rig = *source->info().stereo;
  // Half resolution; 96 disparities there reach 707 * 0.537 / 192 = 2 m; the street's far end.
  StereoDepthConfig config;
  config.num_disparities = 96;
  config.max_depth_m = 40.0;
  auto estimator = StereoDepthEstimator::create(rig, config, &error);
  ASSERT_NE(estimator, nullptr) << error;
  OrbExtractorConfig orb;
  orb.num_features = 2000;
  OrbExtractor extractor(orb);
  CaptureFrame frame;
  for (int i = 0; source->next(&frame, &error) == FrameSource::Status::kFrame; ++i) {
    if (i % 20 != 0) continue;  // frames 0, 20, 40
    DepthImage dense;
    estimator->compute(frame.left, frame.right, &dense);
    const ExtractedFeatures left = extractor.extract(frame.left);
    const ExtractedFeatures right = extractor.extract(frame.right);
    const StereoDepth sparse =
        matchStereo(left, right, rig.intrinsics.fx, rig.baseline_m, StereoMatcherConfig{});
    std::vector<double> relative;
    for (size_t k = 0; k < sparse.depth.size(); ++k) {
      const double z = sparse.depth[k];
      if (!(z >= 3.0 && z <= 40.0)) continue;
      // The dense pixel that holds the keypoint (working resolution: half).
      const int u = static_cast<int>(std::lround((left.keypoints[k].u + 0.5) / 2.0 - 0.5));
      const int v = static_cast<int>(std::lround((left.keypoints[k].v + 0.5) / 2.0 - 0.5));
      if (u < 0 || v < 0 || u >= dense.width || v >= dense.height) continue;
      const float d = dense(u, v);
      if (d > 0.0f) relative.push_back(std::abs(d - z) / z);
    }
    ASSERT_GT(relative.size(), 300u) << "frame " << i;
    std::sort(relative.begin(), relative.end());
    const double median = relative[relative.size() / 2];
    const double p90 = relative[relative.size() * 9 / 10];
    RecordProperty("median_rel_" + std::to_string(i), std::to_string(median));
    RecordProperty("p90_rel_" + std::to_string(i), std::to_string(p90));
    EXPECT_LT(median, 0.025) << "frame " << i;  // 1.4-1.5 % measured
    EXPECT_LT(p90, 0.1) << "frame " << i;       // 3.8-5.3 %
  }
}

TEST(DepthAccuracyTest, ExactCounts) {
  DepthImage exact(4, 2, 2.0f), estimate(2, 1, 0.0f);
  exact(3, 1) = 0.0f;        // second block has a hole: not compared
  estimate(0, 0) = 2.1f;     // 5 % off
  estimate(1, 0) = 9.0f;
  const DepthAccuracy a = compareToExactDepth(estimate, 2, exact);
  EXPECT_EQ(a.reference, 1u);
  EXPECT_EQ(a.compared, 1u);
  EXPECT_NEAR(a.median_abs_m, 0.1, 1e-6);
  EXPECT_NEAR(a.median_rel, 0.05, 1e-6);
  EXPECT_EQ(a.outlier_fraction, 0.0);
  ASSERT_EQ(a.bins.size(), 1u);
  EXPECT_EQ(a.bins[0].z_min_m, 2.0);
  EXPECT_THROW(compareToExactDepth(estimate, 1, exact), std::invalid_argument);
}

}  // namespace
}  // namespace cblox
