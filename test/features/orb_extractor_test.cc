#include "core/features/orb_extractor.h"

#include <algorithm>
#include <cmath>
#include <map>
#include <numeric>
#include <stdexcept>
#include <tuple>

#include <gtest/gtest.h>
#include <opencv2/features2d.hpp>
#include <opencv2/imgproc.hpp>

#include "test/features/feature_test_frames.h"

namespace cblox {
namespace {

using test::matView;
using test::simFrames;

TEST(OrbExtractorTest, LevelSharesFollowOrbSlam2) {
  const OrbExtractor extractor{OrbExtractorConfig{}};
  // 1200 (1 - 1/1.2) / (1 - 1.2^-8) = 260.6 at level 0, then x 1/1.2, the rest on level 7.
  EXPECT_EQ(extractor.featuresPerLevel(), (std::vector<int>{261, 217, 181, 151, 126, 105, 87, 72}));
  OrbExtractorConfig config;
  config.num_features = 1000;
  config.num_levels = 3;
  config.scale_factor = 2.0;
  // 1000 (1/2) / (7/8) = 571.4, 285.7, remainder 143.
  EXPECT_EQ(OrbExtractor(config).featuresPerLevel(), (std::vector<int>{571, 286, 143}));
}

void expectWellFormed(const ExtractedFeatures& f, const OrbExtractorConfig& config,
                      const std::string& name) {
  const int n = config.num_features;
  EXPECT_LE(f.keypoints.size(), static_cast<size_t>(n)) << name;
  EXPECT_GE(f.keypoints.size(), static_cast<size_t>(0.9 * n)) << name;
  ASSERT_EQ(f.descriptors.size(), f.keypoints.size()) << name;
  ASSERT_EQ(f.pyramid.size(), static_cast<size_t>(config.num_levels)) << name;
  std::vector<int> per_level(static_cast<size_t>(config.num_levels), 0);
  int previous_octave = 0;
  for (const Keypoint& kp : f.keypoints) {
    ASSERT_GE(kp.octave, previous_octave) << name;  // grouped by level
    ASSERT_LT(kp.octave, config.num_levels) << name;
    previous_octave = kp.octave;
    ++per_level[static_cast<size_t>(kp.octave)];
    // Level coordinates are integers at least the edge threshold inside the level.
    const float s = f.scales.invScale(kp.octave);
    const float x = kp.u * s, y = kp.v * s;
    EXPECT_NEAR(x, std::round(x), 1e-3f) << name;
    EXPECT_NEAR(y, std::round(y), 1e-3f) << name;
    const cv::Mat& level = f.pyramid[static_cast<size_t>(kp.octave)];
    EXPECT_GE(std::lround(x), OrbExtractorConfig::kEdgeThreshold) << name;
    EXPECT_GE(std::lround(y), OrbExtractorConfig::kEdgeThreshold) << name;
    EXPECT_LT(std::lround(x), level.cols - OrbExtractorConfig::kEdgeThreshold) << name;
    EXPECT_LT(std::lround(y), level.rows - OrbExtractorConfig::kEdgeThreshold) << name;
    EXPECT_GE(kp.angle_deg, 0.0f);
    EXPECT_LT(kp.angle_deg, 360.0f);
    EXPECT_GE(kp.response, static_cast<float>(config.min_fast_threshold)) << name;
  }
  for (int l = 0; l < config.num_levels; ++l) {
    EXPECT_GT(per_level[static_cast<size_t>(l)], 0) << name << " level " << l;
  }
}

TEST(OrbExtractorTest, SimulatorFramesGiveTheWantedCountOnEveryLevel) {
  OrbExtractor extractor{OrbExtractorConfig{}};
  for (const std::string scene : {"room", "hall", "town"}) {
    for (const test::StereoFrame& frame : simFrames(scene, 2)) {
      expectWellFormed(extractor.extract(frame.left), extractor.config(), frame.name);
      expectWellFormed(extractor.extract(frame.right), extractor.config(), frame.name + " right");
    }
  }
  // Other settings: 2000 features, 4 levels of 1.5.
  OrbExtractorConfig config;
  config.num_features = 2000;
  config.num_levels = 4;
  config.scale_factor = 1.5;
  OrbExtractor other(config);
  const auto& room = simFrames("room", 2);
  ASSERT_FALSE(room.empty());
  expectWellFormed(other.extract(room[0].left), config, "room, 2000 features / 4 levels");
}

TEST(OrbExtractorTest, FeaturesAreSpreadOverTheImage) {
  // 8 x 6 grid over the level-0 detection area: cells where FAST at the minimum threshold
  // finds corners hold features, and no cell holds more than 3 times its share (25).
  // Measured on these 6 frames: every cell with at least 2 corners holds at least 8 features
  // (one town cell with a single corner on a roof edge holds none: its quadtree node also
  // covers stronger corners of the next cell); the fullest cell holds 63.
  OrbExtractor extractor{OrbExtractorConfig{}};
  constexpr int kCols = 8, kRows = 6, kE = OrbExtractorConfig::kEdgeThreshold;
  for (const std::string scene : {"room", "hall", "town"}) {
    for (const test::StereoFrame& frame : simFrames(scene, 2)) {
      const ExtractedFeatures f = extractor.extract(frame.left);
      const cv::Mat image = matView(frame.left);
      const int w = image.cols - 2 * kE, h = image.rows - 2 * kE;
      std::vector<int> features(kCols * kRows, 0), corners(kCols * kRows, 0);
      const auto cellOf = [&](float u, float v) {
        const int cx = std::clamp(static_cast<int>((u - kE) * kCols / w), 0, kCols - 1);
        const int cy = std::clamp(static_cast<int>((v - kE) * kRows / h), 0, kRows - 1);
        return static_cast<size_t>(cy * kCols + cx);
      };
      for (const Keypoint& kp : f.keypoints) ++features[cellOf(kp.u, kp.v)];
      std::vector<cv::KeyPoint> fast;
      cv::FAST(image(cv::Rect(kE - 3, kE - 3, w + 6, h + 6)), fast, 7, true);
      for (const cv::KeyPoint& kp : fast) ++corners[cellOf(kp.pt.x + kE - 3, kp.pt.y + kE - 3)];
      int cells_with_corners = 0;
      for (size_t c = 0; c < features.size(); ++c) {
        EXPECT_LE(features[c], 75) << frame.name << " cell " << c;
        if (corners[c] < 2) continue;
        ++cells_with_corners;
        EXPECT_GE(features[c], corners[c] >= 10 ? 4 : 1)
            << frame.name << " cell " << c << " has " << corners[c] << " FAST corners";
      }
      EXPECT_GE(cells_with_corners, 40) << frame.name;  // the sky of town has none
    }
  }
}

TEST(OrbExtractorTest, RotatingTheImageBy90DegreesTurnsAnglesAndKeepsDescriptors) {
  OrbExtractor extractor{OrbExtractorConfig{}};
  std::vector<float> angle_errors;
  std::vector<int> distances;
  for (const std::string scene : {"room", "hall"}) {
    const auto& frames = simFrames(scene, 1);
    ASSERT_FALSE(frames.empty());
    const cv::Mat image = matView(frames[0].left);
    cv::Mat rotated;
    cv::rotate(image, rotated, cv::ROTATE_90_CLOCKWISE);  // (u, v) -> (H - 1 - v, u)
    const ExtractedFeatures a = extractor.extract(image);
    const ExtractedFeatures b = extractor.extract(rotated);
    // Index the original keypoints by (octave, level pixel).
    std::map<std::tuple<int, int, int>, size_t> index;
    for (size_t i = 0; i < a.keypoints.size(); ++i) {
      const Keypoint& kp = a.keypoints[i];
      const float s = a.scales.invScale(kp.octave);
      index[{kp.octave, static_cast<int>(std::lround(kp.u * s)),
             static_cast<int>(std::lround(kp.v * s))}] = i;
    }
    for (size_t j = 0; j < b.keypoints.size(); ++j) {
      const Keypoint& kp = b.keypoints[j];
      const cv::Mat& level = a.pyramid[static_cast<size_t>(kp.octave)];
      const float s = b.scales.invScale(kp.octave);
      const int x = static_cast<int>(std::lround(kp.u * s)),
                y = static_cast<int>(std::lround(kp.v * s));
      const auto it = index.find({kp.octave, y, level.rows - 1 - x});  // back to the original
      if (it == index.end()) continue;
      const Keypoint& original = a.keypoints[it->second];
      float error = kp.angle_deg - original.angle_deg - 90.0f;
      error -= 360.0f * std::round(error / 360.0f);
      angle_errors.push_back(std::abs(error));
      distances.push_back(hammingDistance(a.descriptors[it->second], b.descriptors[j]));
    }
  }
  ASSERT_GT(angle_errors.size(), 500u);
  std::sort(angle_errors.begin(), angle_errors.end());
  std::sort(distances.begin(), distances.end());
  const auto at = [](const auto& v, double q) {
    return v[static_cast<size_t>(q * (v.size() - 1))];
  };
  // Measured (room + hall): 1452 keypoints found in both; angle error median 0.05 deg, 95 %
  // 0.46 deg, max 2.7 deg (fastAtan2 is good to ~0.3 deg; pyramid levels differ slightly);
  // Hamming distance median 1, 95 % 6, max 24 of 256 bits (unrelated ORB descriptors: ~128).
  EXPECT_LT(at(angle_errors, 0.5), 0.3f);
  EXPECT_LT(at(angle_errors, 0.95), 1.5f);
  EXPECT_LT(angle_errors.back(), 6.0f);
  EXPECT_LE(at(distances, 0.5), 4);
  EXPECT_LE(at(distances, 0.95), 15);
  EXPECT_LE(distances.back(), 50);
}

TEST(OrbExtractorTest, IsDeterministicAndOwnsItsPyramid) {
  const auto& frames = simFrames("room", 2);
  ASSERT_EQ(frames.size(), 2u);
  OrbExtractor extractor{OrbExtractorConfig{}};
  const ExtractedFeatures first = extractor.extract(frames[0].left);
  const ExtractedFeatures other = extractor.extract(frames[1].left);  // reuses the buffers
  const ExtractedFeatures again = extractor.extract(matView(frames[0].left));
  ASSERT_EQ(first.keypoints.size(), again.keypoints.size());
  for (size_t i = 0; i < first.keypoints.size(); ++i) {
    EXPECT_EQ(first.keypoints[i].u, again.keypoints[i].u);
    EXPECT_EQ(first.keypoints[i].v, again.keypoints[i].v);
    EXPECT_EQ(first.keypoints[i].angle_deg, again.keypoints[i].angle_deg);
    EXPECT_EQ(first.keypoints[i].octave, again.keypoints[i].octave);
    EXPECT_EQ(first.descriptors[i], again.descriptors[i]);
  }
  // The pyramid of the first result is still the first image's.
  EXPECT_EQ(cv::norm(first.pyramid[0], matView(frames[0].left), cv::NORM_INF), 0.0);
  EXPECT_GT(cv::norm(first.pyramid[0], other.pyramid[0], cv::NORM_INF), 0.0);
  EXPECT_NE(first.pyramid[0].data, frames[0].left.data.data());
}

TEST(OrbExtractorTest, FlatAndTinyImagesGiveNoFeatures) {
  OrbExtractor extractor{OrbExtractorConfig{}};
  const ExtractedFeatures flat = extractor.extract(GrayImage(752, 480, 128));
  EXPECT_TRUE(flat.keypoints.empty());
  EXPECT_EQ(flat.pyramid.size(), 8u);
  // The smallest accepted image: a one-pixel detection area at level 0, nothing above.
  constexpr int kMin = OrbExtractorConfig::kMinImageSide;
  GrayImage tiny(kMin, kMin, 100);
  tiny(kMin / 2, kMin / 2) = 200;
  const ExtractedFeatures one = extractor.extract(tiny);
  ASSERT_EQ(one.keypoints.size(), 1u);
  EXPECT_EQ(one.keypoints[0].u, static_cast<float>(kMin / 2));
  EXPECT_EQ(one.keypoints[0].octave, 0);
}

TEST(OrbExtractorTest, RejectsBadConfigsAndImagesWithAMessage) {
  const auto message = [](const OrbExtractorConfig& c) { return c.validate(); };
  EXPECT_EQ(message(OrbExtractorConfig{}), "");
  OrbExtractorConfig c;
  c.num_features = 0;
  EXPECT_NE(message(c).find("num_features"), std::string::npos);
  c = {};
  c.num_levels = 0;
  EXPECT_NE(message(c).find("num_levels"), std::string::npos);
  c = {};
  c.scale_factor = 1.0;
  EXPECT_NE(message(c).find("scale_factor"), std::string::npos);
  c = {};
  c.initial_fast_threshold = 0;
  EXPECT_NE(message(c).find("initial_fast_threshold"), std::string::npos);
  c = {};
  c.min_fast_threshold = 21;
  EXPECT_NE(message(c).find("min_fast_threshold"), std::string::npos);
  c = {};
  c.min_fast_threshold = 0;
  EXPECT_NE(message(c).find("min_fast_threshold"), std::string::npos);
  try {
    OrbExtractor bad(c);
    FAIL() << "an invalid config was accepted";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("min_fast_threshold"), std::string::npos) << e.what();
  }

  OrbExtractor extractor{OrbExtractorConfig{}};
  const auto error = [&](const auto& image) {
    try {
      extractor.extract(image);
    } catch (const std::invalid_argument& e) {
      return std::string(e.what());
    }
    return std::string("no error");
  };
  EXPECT_NE(error(GrayImage()).find("empty"), std::string::npos);
  EXPECT_NE(error(cv::Mat()).find("empty"), std::string::npos);
  EXPECT_NE(error(GrayImage(38, 480)).find("smaller than the border"), std::string::npos);
  EXPECT_NE(error(GrayImage(752, 20)).find("smaller than the border"), std::string::npos);
  EXPECT_NE(error(cv::Mat(480, 752, CV_8UC3)).find("CV_8UC1"), std::string::npos);
  GrayImage broken(100, 100);
  broken.data.resize(50);
  EXPECT_NE(error(broken).find("pixels"), std::string::npos);
}

}  // namespace
}  // namespace cblox
