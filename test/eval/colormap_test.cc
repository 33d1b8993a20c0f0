#include "core/eval/colormap.h"

#include <cmath>
#include <limits>
#include <vector>

#include <gtest/gtest.h>

namespace cblox {
namespace {

// Relative luminance Y of an sRGB colour (linearised, Rec. 709 weights).
double luminance(const Color& c) {
  const auto linear = [](uint8_t v) {
    const double s = v / 255.0;
    return s <= 0.04045 ? s / 12.92 : std::pow((s + 0.055) / 1.055, 2.4);
  };
  return 0.2126 * linear(c.r) + 0.7152 * linear(c.g) + 0.0722 * linear(c.b);
}

TEST(ColormapTest, ViridisEndpointsAndClamping) {
  EXPECT_EQ(colormap(0.0), (Color{68, 1, 84}));
  EXPECT_EQ(colormap(1.0), (Color{253, 231, 37}));
  EXPECT_EQ(colormap(-3.0), colormap(0.0));
  EXPECT_EQ(colormap(7.0), colormap(1.0));
  EXPECT_EQ(colormap(std::numeric_limits<double>::quiet_NaN()), colormap(0.0));
  EXPECT_EQ(colormap(std::numeric_limits<double>::infinity()), colormap(1.0));
  // Middle of viridis is teal: green and blue well above red.
  const Color mid = colormap(0.5);
  EXPECT_GT(mid.g, mid.r + 60);
  EXPECT_GT(mid.b, mid.r + 60);
}

TEST(ColormapTest, LuminanceIncreasesMonotonically) {
  // Strictly increasing at steps of 1/50; between neighbouring 8-bit entries rounding may make
  // it dip slightly (by < 1e-3; twice in OpenCV's table).
  for (int i = 1; i <= 50; ++i) {
    EXPECT_GT(luminance(colormap(i / 50.0)), luminance(colormap((i - 1) / 50.0))) << i;
  }
  double previous = luminance(colormap(0.0));
  for (int i = 1; i <= 1000; ++i) {
    const double y = luminance(colormap(i / 1000.0));
    EXPECT_GT(y, previous - 1e-3) << "t = " << i / 1000.0;
    previous = y;
  }
}

TEST(NiceTicksTest, PicksOneTwoFiveSteps) {
  const std::vector<double> unit = niceTicks(0.0, 1.0, 5);
  ASSERT_EQ(unit.size(), 6u);
  for (size_t i = 0; i < unit.size(); ++i) EXPECT_NEAR(unit[i], 0.2 * i, 1e-12);
  const std::vector<double> shifted = niceTicks(-0.13, 0.42, 5);
  ASSERT_EQ(shifted.size(), 6u);  // raw step 0.11 -> 0.1
  EXPECT_NEAR(shifted.front(), -0.1, 1e-12);
  EXPECT_NEAR(shifted.back(), 0.4, 1e-12);
  const std::vector<double> large = niceTicks(0.0, 37.0, 4);  // raw 9.25 -> step 10
  ASSERT_EQ(large.size(), 4u);
  EXPECT_EQ(large.back(), 30.0);
  EXPECT_TRUE(niceTicks(1.0, 1.0, 5).empty());
  EXPECT_TRUE(niceTicks(2.0, 1.0, 5).empty());
  EXPECT_TRUE(niceTicks(0.0, std::numeric_limits<double>::infinity(), 5).empty());
  EXPECT_EQ(niceTicks(0.0, 1.0, 0), niceTicks(0.0, 1.0, 1));
}

TEST(NiceTicksTest, FormatsWithTheStepsDecimals) {
  EXPECT_EQ(formatTick(25.0, 5.0), "25");
  EXPECT_EQ(formatTick(0.30000000000000004, 0.1), "0.3");
  EXPECT_EQ(formatTick(0.25, 0.05), "0.25");
  EXPECT_EQ(formatTick(0.75, 0.25), "0.75");
  EXPECT_EQ(formatTick(-1e-17, 0.1), "0.0");
  EXPECT_EQ(formatTick(-0.0001, 1.0), "0");  // never "-0"
  EXPECT_EQ(formatTick(-2.0, 0.5), "-2.0");
  EXPECT_EQ(formatTick(1.5, std::nan("")), "2");
}

TEST(DrawColorBarTest, FillsTheBarTopToBottomWithFrameAndLabels) {
  ColorImage image(200, 300, Color{255, 255, 255});
  drawColorBar(&image, 20, 30, 20, 200, 0.0, 0.5, "m");
  EXPECT_EQ(image(25, 30), colormap(1.0));   // top row: max_value
  EXPECT_EQ(image(25, 229), colormap(0.0));  // bottom row: min_value
  EXPECT_EQ(image(39, 130), colormap(1.0 - 100.0 / 199.0));
  EXPECT_EQ(image(19, 100), (Color{0, 0, 0}));  // frame
  EXPECT_EQ(image(40, 100), (Color{0, 0, 0}));
  EXPECT_EQ(image(30, 29), (Color{0, 0, 0}));
  EXPECT_EQ(image(30, 230), (Color{0, 0, 0}));
  // Tick labels to the right of the bar and the unit above it: dark text pixels.
  const auto dark_pixels = [&image](int u0, int u1, int v0, int v1) {
    int count = 0;
    for (int v = v0; v < v1; ++v) {
      for (int u = u0; u < u1; ++u) count += image(u, v).r < 128 ? 1 : 0;
    }
    return count;
  };
  EXPECT_GT(dark_pixels(47, 120, 20, 240), 50);
  EXPECT_GT(dark_pixels(20, 40, 10, 24), 5);
  EXPECT_EQ(dark_pixels(130, 200, 0, 300), 0);
  EXPECT_EQ(dark_pixels(0, 200, 260, 300), 0);
}

TEST(DrawColorBarTest, ClipsAndIgnoresBadArguments) {
  ColorImage image(50, 40, Color{255, 255, 255});
  drawColorBar(&image, -10, -50, 30, 300, 0.0, 1.0, "deg");  // mostly outside
  EXPECT_EQ(image(0, 0), colormap(1.0 - 50.0 / 299.0));
  drawColorBar(&image, 10, 10, 10, 10, 1.0, 1.0, "");  // empty range: one label
  drawColorBar(&image, 10, 10, 10, 10, 0.0, std::nan(""), "");
  const ColorImage before = image;
  drawColorBar(&image, 10, 10, 0, 10, 0.0, 1.0, "m");
  drawColorBar(&image, 10, 10, 10, -1, 0.0, 1.0, "m");
  EXPECT_EQ(image.data, before.data);
  drawColorBar(nullptr, 0, 0, 10, 10, 0.0, 1.0, "m");
  ColorImage empty;
  drawColorBar(&empty, 0, 0, 10, 10, 0.0, 1.0, "m");
  ColorImage malformed(10, 10);
  malformed.data.resize(5);
  drawColorBar(&malformed, 0, 0, 10, 10, 0.0, 1.0, "m");
}

}  // namespace
}  // namespace cblox
