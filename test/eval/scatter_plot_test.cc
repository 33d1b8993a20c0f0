#include "core/eval/scatter_plot.h"

#include <cmath>
#include <limits>
#include <string>

#include <gtest/gtest.h>
#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>

#include "test/test_support/temp_dir.h"

namespace cblox {
namespace {

// With all values positive both axes start at 0 and end 8 % beyond the largest value; the
// plot area is 80 px from the left and 40 px from the top (a title), 110 px narrower and
// 95 px lower than the image. Each marker's centre pixel has its series' colour.
TEST(ScatterPlotTest, MarkersSitWhereTheAxesSayInTheirSeriesColour) {
  const std::vector<ScatterPoint> points = {
      {100.0, 10.0, "a", 0}, {200.0, 20.0, "b", 1}, {150.0, 5.0, "c", 1}};
  ScatterPlotConfig options;
  options.title = "size vs error";
  options.x_label = "blocks";
  options.y_label = "mm";
  std::string error;
  const std::optional<ColorImage> image = renderScatterPlot(points, options, &error);
  ASSERT_TRUE(image.has_value()) << error;
  ASSERT_EQ(image->width, 1000);
  ASSERT_EQ(image->height, 700);
  const int area_x = 80, area_y = 40, area_w = 1000 - 110, area_h = 700 - 40 - 55;
  const double x_max = 200.0 * 1.08, y_max = 20.0 * 1.08;
  auto centre = [&](const ScatterPoint& p) {
    const int u = static_cast<int>(std::lround(area_x + p.x / x_max * (area_w - 1)));
    const int v = static_cast<int>(std::lround(area_y + area_h - 1 - p.y / y_max * (area_h - 1)));
    return image->data[static_cast<size_t>(v) * image->width + u];
  };
  const Color grey_blue{90, 110, 140}, red{214, 39, 40};
  EXPECT_EQ(centre(points[0]), grey_blue);
  EXPECT_EQ(centre(points[1]), red);
  EXPECT_EQ(centre(points[2]), red);
  // The origin corner of the frame is black; outside the frame the background is white.
  EXPECT_EQ(image->data[static_cast<size_t>(area_y + area_h - 1) * image->width + area_x],
            (Color{0, 0, 0}));
  EXPECT_EQ(image->data[static_cast<size_t>(5) * image->width + 995], (Color{255, 255, 255}));
}

TEST(ScatterPlotTest, WritesAPngOfTheConfiguredSize) {
  test::TempDir dir("cblox_scatter");
  const std::string path = (dir.path() / "plot.png").string();
  ScatterPlotConfig options;
  options.width = 640;
  options.height = 480;
  std::string error;
  ASSERT_TRUE(writeScatterPlotPng(path, {{1.0, 1.0, "", 0}}, options, &error)) << error;
  const cv::Mat read = cv::imread(path);
  EXPECT_EQ(read.cols, 640);
  EXPECT_EQ(read.rows, 480);
}

TEST(ScatterPlotTest, FailsWithAMessage) {
  std::string error;
  EXPECT_FALSE(renderScatterPlot({}, {}, &error).has_value());
  EXPECT_NE(error.find("no point"), std::string::npos);
  EXPECT_FALSE(renderScatterPlot({{std::nan(""), 1.0, "p", 0}}, {}, &error).has_value());
  EXPECT_NE(error.find("'p' is not finite"), std::string::npos);
  EXPECT_FALSE(renderScatterPlot({{1.0, 1.0, "q", -1}}, {}, &error).has_value());
  EXPECT_NE(error.find("negative series"), std::string::npos);
  ScatterPlotConfig narrow;
  narrow.width = 100;
  EXPECT_FALSE(renderScatterPlot({{1.0, 1.0, "", 0}}, narrow, &error).has_value());
  EXPECT_NE(error.find("width"), std::string::npos);
  EXPECT_FALSE(writeScatterPlotPng("/nonexistent/dir/p.png", {{1.0, 1.0, "", 0}}, {}, &error));
  EXPECT_NE(error.find("/nonexistent/dir/p.png"), std::string::npos);
}

}  // namespace
}  // namespace cblox
