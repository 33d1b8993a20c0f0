#include "core/features/scale_pyramid.h"

#include <cmath>
#include <limits>
#include <stdexcept>

#include <gtest/gtest.h>
#include <opencv2/imgproc.hpp>

namespace cblox {
namespace {

TEST(ScalePyramidTest, ScalesAndSigmasArePowersOfTheFactor) {
  const ScalePyramid p(8, 1.2);
  ASSERT_EQ(p.numLevels(), 8);
  EXPECT_EQ(p.scaleFactor(), 1.2);
  float s = 1.0f;
  for (int i = 0; i < 8; ++i) {
    EXPECT_EQ(p.scale(i), s) << i;  // repeated float products, as ORB-SLAM2
    EXPECT_NEAR(p.scale(i), std::pow(1.2, i), 1e-5 * std::pow(1.2, i)) << i;
    EXPECT_EQ(p.invScale(i), 1.0f / s) << i;
    EXPECT_EQ(p.sigma2(i), s * s) << i;
    EXPECT_EQ(p.invSigma2(i), 1.0f / (s * s)) << i;
    s *= 1.2f;
  }
  EXPECT_EQ(p.scale(0), 1.0f);
  EXPECT_NEAR(p.scale(7), 3.5831808f, 1e-6f);
}

TEST(ScalePyramidTest, LevelSizesRoundTheScaledSize) {
  const ScalePyramid p(8, 1.2);
  const cv::Size base(752, 480);
  EXPECT_EQ(p.levelSize(base, 0), base);
  EXPECT_EQ(p.levelSize(base, 1), cv::Size(627, 400));  // 626.67, 400
  EXPECT_EQ(p.levelSize(base, 2), cv::Size(522, 333));  // 522.22, 333.33
  EXPECT_EQ(p.levelSize(base, 7), cv::Size(210, 134));  // 209.87, 133.96
}

TEST(ScalePyramidTest, BuildChainsLinearResizesFromTheLevelAbove) {
  cv::Mat image(97, 131, CV_8UC1);
  cv::randu(image, 0, 256);
  const ScalePyramid p(4, 1.5);
  const std::vector<cv::Mat> levels = p.build(image);
  ASSERT_EQ(levels.size(), 4u);
  // Level 0 is a copy, not a view of the input.
  EXPECT_NE(levels[0].data, image.data);
  EXPECT_EQ(cv::norm(levels[0], image, cv::NORM_INF), 0.0);
  for (int i = 1; i < 4; ++i) {
    ASSERT_EQ(levels[static_cast<size_t>(i)].size(), p.levelSize(image.size(), i));
    EXPECT_TRUE(levels[static_cast<size_t>(i)].isContinuous());
    cv::Mat expected;
    cv::resize(levels[static_cast<size_t>(i - 1)], expected, p.levelSize(image.size(), i), 0, 0,
               cv::INTER_LINEAR);
    EXPECT_EQ(cv::norm(levels[static_cast<size_t>(i)], expected, cv::NORM_INF), 0.0) << i;
  }
  EXPECT_EQ(p.levelSize(image.size(), 3), cv::Size(39, 29));  // 131 / 3.375, 97 / 3.375
}

TEST(ScalePyramidTest, LevelsTooSmallToExistAreEmpty) {
  const ScalePyramid p(6, 4.0);
  const std::vector<cv::Mat> levels = p.build(cv::Mat(300, 300, CV_8UC1, cv::Scalar(9)));
  EXPECT_EQ(levels[4].size(), cv::Size(1, 1));  // 300 / 256 = 1.17
  EXPECT_TRUE(levels[5].empty());               // 300 / 1024 rounds to 0
}

TEST(ScalePyramidTest, RejectsBadParametersAndImages) {
  EXPECT_THROW(ScalePyramid(0, 1.2), std::invalid_argument);
  EXPECT_THROW(ScalePyramid(33, 1.2), std::invalid_argument);
  EXPECT_THROW(ScalePyramid(8, 1.0), std::invalid_argument);
  EXPECT_THROW(ScalePyramid(8, 4.5), std::invalid_argument);
  EXPECT_THROW(ScalePyramid(8, std::numeric_limits<double>::quiet_NaN()), std::invalid_argument);
  EXPECT_NE(ScalePyramid::validate(8, 0.9).find("scale_factor"), std::string::npos);
  EXPECT_NE(ScalePyramid::validate(-1, 1.2).find("num_levels"), std::string::npos);
  EXPECT_EQ(ScalePyramid::validate(8, 1.2), "");
  const ScalePyramid p(8, 1.2);
  EXPECT_THROW(p.build(cv::Mat()), std::invalid_argument);
  EXPECT_THROW(p.build(cv::Mat(50, 50, CV_8UC3)), std::invalid_argument);
}

}  // namespace
}  // namespace cblox
