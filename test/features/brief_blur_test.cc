#include "core/features/brief_blur.h"

#include <cmath>
#include <random>
#include <stdexcept>

#include <gtest/gtest.h>
#include <opencv2/imgproc.hpp>

#include "core/features/scale_pyramid.h"
#include "core/geometry/cpu_features.h"
#include "test/features/feature_test_frames.h"

namespace cblox {
namespace {

// The number of differing pixels between two images of the same size.
int differing(const cv::Mat& a, const cv::Mat& b) {
  EXPECT_EQ(a.size(), b.size());
  cv::Mat diff;
  cv::compare(a, b, diff, cv::CMP_NE);
  return cv::countNonZero(diff);
}

TEST(BriefBlurTest, ConstantImagesStayConstant) {
  // The float kernel sums to 1 within rounding: every constant, including 0 and 255, is kept.
  BriefBlur blur;
  for (const int c : {0, 1, 100, 200, 254, 255}) {
    const cv::Mat image(37, 53, CV_8UC1, cv::Scalar(c));
    cv::Mat out;
    blur.apply(image, &out);
    EXPECT_EQ(cv::countNonZero(out != c), 0) << "constant " << c;
  }
}

TEST(BriefBlurTest, AnImpulseGivesTheOuterProductOfTheKernel) {
  // One pixel of 255 far from the borders: out(x, y) = round(255 g_i g_j) with the sampled,
  // normalised Gaussian g_i = exp(-(i - 3)^2 / 8) / sum, and 0 beyond the kernel's reach.
  double g[7], sum = 0.0;
  for (int i = 0; i < 7; ++i) sum += g[i] = std::exp(-(i - 3) * (i - 3) / 8.0);
  cv::Mat image(40, 48, CV_8UC1, cv::Scalar(0));
  image.at<uint8_t>(20, 25) = 255;
  BriefBlur blur;
  cv::Mat out;
  blur.apply(image, &out);
  for (int y = 0; y < image.rows; ++y) {
    for (int x = 0; x < image.cols; ++x) {
      const int i = y - 20 + 3, j = x - 25 + 3;
      const int expected = i >= 0 && i < 7 && j >= 0 && j < 7
                               ? static_cast<int>(std::lround(255 * g[i] * g[j] / (sum * sum)))
                               : 0;
      ASSERT_EQ(out.at<uint8_t>(y, x), expected) << "at " << x << "," << y;
    }
  }
  EXPECT_EQ(out.at<uint8_t>(20, 25), 12);  // 255 * 0.2161^2 = 11.91
}

TEST(BriefBlurTest, SameBytesAsOpenCvsOrbOnNoiseOfEverySize) {
  // Sizes around the 16-pixel blocks (the last block overlaps) and the smallest heights the
  // reflection allows; windows of a larger buffer (row step != width) too; then many full-size
  // frames, since a difference in the order of the float operations shows only where a sum
  // lands near a rounding tie (a few pixels per million).
  if (!cpuHasAvx2Fma()) std::printf("no AVX2 and FMA here: apply() is applyOpenCv()\n");
  std::mt19937 rng(3);
  BriefBlur blur, reference;
  for (const cv::Size size : {cv::Size(16, 4), cv::Size(17, 5), cv::Size(31, 7), cv::Size(32, 8),
                              cv::Size(33, 9), cv::Size(47, 100), cv::Size(211, 157),
                              cv::Size(752, 480), cv::Size(5, 30), cv::Size(300, 3)}) {
    for (const bool window : {false, true}) {
      cv::Mat buffer(size.height + 9, size.width + 21, CV_8UC1);
      cv::randu(buffer, 0, 256);
      const cv::Mat image = window ? buffer(cv::Rect(cv::Point(13, 5), size))
                                   : buffer(cv::Rect(cv::Point(0, 0), size)).clone();
      cv::Mat ours, theirs;
      blur.apply(image, &ours);
      reference.applyOpenCv(image, &theirs);
      ASSERT_EQ(ours.size(), size);
      EXPECT_EQ(differing(ours, theirs), 0) << size << (window ? " window" : "");
    }
  }
  int differ = 0;
  for (int i = 0; i < 30; ++i) {
    cv::Mat image(480, 752, CV_8UC1);
    cv::randu(image, 0, 256);
    cv::Mat ours, theirs;
    blur.apply(image, &ours);
    reference.applyOpenCv(image, &theirs);
    differ += differing(ours, theirs);
  }
  EXPECT_EQ(differ, 0) << "in 30 frames of noise";
  // Extremes side by side: a 0/255 checkerboard.
  cv::Mat board(64, 80, CV_8UC1);
  for (int y = 0; y < board.rows; ++y) {
    for (int x = 0; x < board.cols; ++x) board.at<uint8_t>(y, x) = (x + y) % 2 ? 255 : 0;
  }
  cv::Mat ours, theirs;
  blur.apply(board, &ours);
  reference.applyOpenCv(board, &theirs);
  EXPECT_EQ(differing(ours, theirs), 0);
}

TEST(BriefBlurTest, SameBytesAsOpenCvsOrbOnEveryPyramidLevel) {
  const ScalePyramid scales(8, 1.2);
  BriefBlur blur, reference;
  for (const std::string scene : {"room", "town"}) {
    const auto& frames = test::simFrames(scene, 1);
    ASSERT_FALSE(frames.empty());
    const std::vector<cv::Mat> levels = scales.build(test::matView(frames[0].left));
    for (size_t l = 0; l < levels.size(); ++l) {
      cv::Mat ours, theirs;
      blur.apply(levels[l], &ours);
      reference.applyOpenCv(levels[l], &theirs);
      EXPECT_EQ(differing(ours, theirs), 0) << scene << " level " << l;
    }
  }
}

TEST(BriefBlurTest, RejectsEmptyAndNonGreyImages) {
  BriefBlur blur;
  cv::Mat out;
  EXPECT_THROW(blur.apply(cv::Mat(), &out), std::invalid_argument);
  EXPECT_THROW(blur.apply(cv::Mat(20, 20, CV_8UC3, cv::Scalar(0)), &out), std::invalid_argument);
  EXPECT_THROW(blur.applyOpenCv(cv::Mat(20, 20, CV_16UC1, cv::Scalar(0)), &out),
               std::invalid_argument);
}

}  // namespace
}  // namespace cblox
