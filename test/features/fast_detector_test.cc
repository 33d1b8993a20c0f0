#include "core/features/fast_detector.h"

#include <random>
#include <vector>

#include <gtest/gtest.h>
#include <opencv2/features2d.hpp>
#include <opencv2/imgproc.hpp>

#include "test/features/feature_test_frames.h"

namespace cblox {
namespace {

// Our corners must be cv::FAST's, in the same order with the same scores.
void expectSameAsOpenCv(const cv::Mat& image, int threshold, const std::string& what) {
  std::vector<cv::KeyPoint> expected;
  cv::FAST(image, expected, threshold, true);
  FastDetector detector;
  std::vector<FastCorner> corners;
  detector.detect(image, threshold, &corners);
  ASSERT_EQ(corners.size(), expected.size()) << what << " threshold " << threshold;
  for (size_t i = 0; i < corners.size(); ++i) {
    ASSERT_EQ(static_cast<float>(corners[i].x), expected[i].pt.x) << what << " #" << i;
    ASSERT_EQ(static_cast<float>(corners[i].y), expected[i].pt.y) << what << " #" << i;
    ASSERT_EQ(static_cast<float>(corners[i].score), expected[i].response) << what << " #" << i;
  }
}

TEST(FastDetectorTest, EqualsOpenCvFastOnSimulatorImages) {
  for (const std::string scene : {"room", "town"}) {
    const auto& frames = test::simFrames(scene, 1);
    ASSERT_FALSE(frames.empty());
    const cv::Mat image = test::matView(frames[0].left);
    for (const int threshold : {5, 7, 20, 60, 254, 255}) {
      expectSameAsOpenCv(image, threshold, scene);
    }
    // A window of the image (step != width), odd sizes, a half-size level.
    expectSameAsOpenCv(image(cv::Rect(13, 17, 301, 203)), 7, scene + " window");
    cv::Mat small;
    cv::resize(image, small, cv::Size(), 0.4, 0.4, cv::INTER_LINEAR);
    expectSameAsOpenCv(small, 12, scene + " small");
  }
}

TEST(FastDetectorTest, EqualsOpenCvFastOnNoiseAndTinyImages) {
  std::mt19937 rng(3);
  // Widths for every code path: scalar (< 22), 16 lanes (22-37, with an overlapping last
  // block from 23 on), 32 lanes where the CPU has AVX2 (>= 38).
  for (const cv::Size size : {cv::Size(7, 7), cv::Size(8, 9), cv::Size(21, 7), cv::Size(22, 40),
                              cv::Size(30, 30), cv::Size(37, 12), cv::Size(38, 12),
                              cv::Size(40, 22), cv::Size(64, 64), cv::Size(257, 131)}) {
    cv::Mat noise(size, CV_8UC1);
    cv::randu(noise, 0, 256);
    for (const int threshold : {5, 30, 90}) {
      expectSameAsOpenCv(noise, threshold,
                         "noise " + std::to_string(size.width) + "x" + std::to_string(size.height));
    }
    // Saturated: bright and dark extremes, where centre +- threshold clips.
    cv::Mat binary;
    cv::threshold(noise, binary, 127, 255, cv::THRESH_BINARY);
    expectSameAsOpenCv(binary, 20, "binary");
  }
  FastDetector detector;
  std::vector<FastCorner> corners = {{1, 1, 1}};
  detector.detect(cv::Mat(6, 100, CV_8UC1, cv::Scalar(0)), 10, &corners);
  EXPECT_TRUE(corners.empty());
}

}  // namespace
}  // namespace cblox
