#include "core/eval/trajectory_plot.h"

#include <cmath>
#include <filesystem>
#include <string>

#include <gtest/gtest.h>
#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>

#include "test/test_support/temp_dir.h"

namespace cblox {
namespace {

namespace fs = std::filesystem;

// A loop of about 4 m x 3 m around (1, 2) and an estimate drifting away from it.
void makeTrajectories(StampedTrajectory* truth, StampedTrajectory* estimate) {
  for (int i = 0; i < 200; ++i) {
    const double a = 2.0 * M_PI * i / 200.0;
    const Eigen::Quaterniond q(Eigen::AngleAxisd(a, Eigen::Vector3d::UnitZ()));
    const Eigen::Vector3d p(1.0 + 2.0 * std::cos(a), 2.0 + 1.5 * std::sin(a),
                            0.1 * std::sin(3 * a));
    truth->push_back({0.1 * i, Transformationd(q, p)});
    estimate->push_back(
        {0.1 * i, Transformationd(q, p + Eigen::Vector3d(0.002 * i, -0.001 * i, 0.0))});
  }
}

// Pixels of exactly `color` in a BGR image read by cv::imread.
int countColor(const cv::Mat& bgr, const Color& color) {
  int count = 0;
  for (int v = 0; v < bgr.rows; ++v) {
    for (int u = 0; u < bgr.cols; ++u) {
      const cv::Vec3b& p = bgr.at<cv::Vec3b>(v, u);
      count += p[2] == color.r && p[1] == color.g && p[0] == color.b ? 1 : 0;
    }
  }
  return count;
}

class TrajectoryPlotTest : public testing::Test {
 protected:
  void SetUp() override { makeTrajectories(&truth_, &estimate_); }
  test::TempDir dir_{"cblox_plot"};
  StampedTrajectory truth_;
  StampedTrajectory estimate_;
};

TEST_F(TrajectoryPlotTest, WritesPngWithBothTrajectories) {
  TrajectoryPlotConfig options;
  options.title = "ATE RMSE 0.034 m";
  const std::string path = dir_.file("plot.png");
  std::string error;
  ASSERT_TRUE(writeTrajectoryPlotPng(path, truth_, estimate_, options, &error)) << error;
  const cv::Mat image = cv::imread(path, cv::IMREAD_COLOR);
  ASSERT_FALSE(image.empty());
  EXPECT_EQ(image.cols, 1000);
  EXPECT_EQ(image.rows, 800);
  // The lines (not only the legend samples and start markers) are in the exact colours.
  EXPECT_GT(countColor(image, options.ground_truth_color), 1000);
  EXPECT_GT(countColor(image, options.estimate_color), 1000);
  // White background dominates; the corners are white.
  EXPECT_GT(countColor(image, Color{255, 255, 255}), image.rows * image.cols / 2);
  EXPECT_EQ(image.at<cv::Vec3b>(0, 0), cv::Vec3b(255, 255, 255));
  EXPECT_EQ(image.at<cv::Vec3b>(799, 999), cv::Vec3b(255, 255, 255));
}

TEST_F(TrajectoryPlotTest, EqualAxisScaling) {
  // A 4 m x 1 m rectangle in a square image: x spans 4 times as many pixels as y.
  StampedTrajectory box;
  const double corners[5][2] = {{0, 0}, {4, 0}, {4, 1}, {0, 1}, {0, 0}};
  for (int i = 0; i < 5; ++i) {
    box.push_back({1.0 * i, Transformationd(Eigen::Quaterniond::Identity(),
                                            Eigen::Vector3d(corners[i][0], corners[i][1], 0.0))});
  }
  TrajectoryPlotConfig options;
  options.width = 600;
  options.height = 600;
  std::string error;
  const auto image = renderTrajectoryPlot(box, {}, options, &error);
  ASSERT_TRUE(image.has_value()) << error;
  // The middle row crosses the two short sides, the middle column the two long ones.
  int u_first = -1, u_last = -1, v_first = -1, v_last = -1;
  for (int u = 0; u < image->width; ++u) {
    if ((*image)(u, 300) == options.ground_truth_color) {
      if (u_first < 0) u_first = u;
      u_last = u;
    }
  }
  for (int v = 0; v < image->height; ++v) {
    if ((*image)(300, v) == options.ground_truth_color) {
      if (v_first < 0) v_first = v;
      v_last = v;
    }
  }
  ASSERT_GE(u_first, 0);
  ASSERT_GE(v_first, 0);
  // Outer edges: 4 m and 1 m plus about one line width.
  const double x_pixels = u_last - u_first - 1;
  const double y_pixels = v_last - v_first - 1;
  EXPECT_NEAR(x_pixels / y_pixels, 4.0, 0.1) << x_pixels << " x " << y_pixels;
  EXPECT_GT(x_pixels, 400);  // fills the plot width (510 px) but for the 5 % margins
}

TEST_F(TrajectoryPlotTest, EstimateMayBeEmptyAndSizeIsConfigurable) {
  TrajectoryPlotConfig options;
  options.width = 640;
  options.height = 480;
  const std::string path = dir_.file("gt_only.png");
  std::string error;
  ASSERT_TRUE(writeTrajectoryPlotPng(path, truth_, {}, options, &error)) << error;
  const cv::Mat image = cv::imread(path, cv::IMREAD_COLOR);
  ASSERT_FALSE(image.empty());
  EXPECT_EQ(image.cols, 640);
  EXPECT_EQ(image.rows, 480);
  EXPECT_GT(countColor(image, options.ground_truth_color), 500);
  EXPECT_EQ(countColor(image, options.estimate_color), 0);

  // A single pose still plots (1 m x 1 m box).
  EXPECT_TRUE(renderTrajectoryPlot({truth_.front()}, {}, options, &error).has_value()) << error;
}

TEST_F(TrajectoryPlotTest, FailsWithAMessage) {
  TrajectoryPlotConfig options;
  std::string error;
  const std::string unwritable = dir_.file("no_such_dir/plot.png");
  EXPECT_FALSE(writeTrajectoryPlotPng(unwritable, truth_, estimate_, options, &error));
  EXPECT_NE(error.find(unwritable + ": cannot open for writing"), std::string::npos) << error;
  EXPECT_FALSE(fs::exists(unwritable));

  EXPECT_FALSE(writeTrajectoryPlotPng(dir_.file("a.png"), {}, estimate_, options, &error));
  EXPECT_NE(error.find("the ground truth is empty"), std::string::npos) << error;

  StampedTrajectory bad = estimate_;
  bad[7].T_G_C =
      Transformationd(Eigen::Quaterniond::Identity(), Eigen::Vector3d(0.0, std::nan(""), 0.0));
  EXPECT_FALSE(renderTrajectoryPlot(truth_, bad, options, &error).has_value());
  EXPECT_NE(error.find("estimate position 7 is not finite"), std::string::npos) << error;

  options.width = 50;
  EXPECT_FALSE(renderTrajectoryPlot(truth_, estimate_, options, &error).has_value());
  EXPECT_NE(error.find("width must be in [200, 10000] pixels, got 50"), std::string::npos) << error;
  options = TrajectoryPlotConfig{};
  options.line_thickness = 0;
  EXPECT_NE(options.validate().find("line_thickness"), std::string::npos);

  EXPECT_FALSE(writeColorImagePng(dir_.file("empty.png"), ColorImage{}, &error));
  EXPECT_NE(error.find("empty or malformed image"), std::string::npos) << error;
}

}  // namespace
}  // namespace cblox
