#include "drivers/libcamera/libcamera_format.h"

#include <string>
#include <utility>
#include <vector>

#include <gtest/gtest.h>
#include <libcamera/formats.h>

#include "test/test_support/contains.h"

namespace cblox {
namespace {

namespace formats = libcamera::formats;
using test::contains;

// Every supported format, with the cblox layout of the same bytes (pixel_format.h).
const std::vector<std::pair<libcamera::PixelFormat, PixelFormat>>& supported() {
  static const std::vector<std::pair<libcamera::PixelFormat, PixelFormat>> table = {
      {formats::R8, PixelFormat::kGrey},       {formats::YUYV, PixelFormat::kYuyv},
      {formats::UYVY, PixelFormat::kUyvy},     {formats::NV12, PixelFormat::kNv12},
      {formats::YUV420, PixelFormat::kYuv420}, {formats::RGB888, PixelFormat::kBgr24},
      {formats::BGR888, PixelFormat::kRgb24},  {formats::XRGB8888, PixelFormat::kXrgb8888},
      {formats::MJPEG, PixelFormat::kMjpeg},
  };
  return table;
}

TEST(LibcameraFormat, MapsEverySupportedFormatExactly) {
  for (const auto& [libcamera_format, format] : supported()) {
    SCOPED_TRACE(libcamera_format.toString());
    EXPECT_EQ(pixelFormatFromLibcamera(libcamera_format), format);
    EXPECT_EQ(libcameraFormatOf(format), libcamera_format);
    // The same answer as the shared DRM-fourcc table of drivers/pixel.
    EXPECT_EQ(pixelFormatFromDrmFourcc(libcamera_format.fourcc()), format);
  }
  // The DRM names count little-endian words: libcamera's RGB888 is B G R in memory.
  EXPECT_EQ(pixelFormatFromLibcamera(formats::RGB888), PixelFormat::kBgr24);
  EXPECT_EQ(pixelFormatFromLibcamera(formats::BGR888), PixelFormat::kRgb24);
}

TEST(LibcameraFormat, RefusesUnsupportedFormats) {
  for (const libcamera::PixelFormat& format :
       {formats::SRGGB10, formats::SBGGR8, formats::R10, formats::NV21, formats::NV16,
        formats::YVYU, formats::VYUY, formats::YVU420, formats::XBGR8888, formats::ARGB8888,
        formats::RGB565, libcamera::PixelFormat()}) {
    EXPECT_FALSE(pixelFormatFromLibcamera(format).has_value()) << format.toString();
  }
  // A modifier (tiled or compressed layout) is not the plain layout.
  EXPECT_FALSE(pixelFormatFromLibcamera(libcamera::PixelFormat(formats::YUYV.fourcc(), 1)));
  // libcamera 0.0.3 has no 16-bit grey or depth stream format.
  EXPECT_FALSE(libcameraFormatOf(PixelFormat::kY16).has_value());
  EXPECT_FALSE(libcameraFormatOf(PixelFormat::kZ16).has_value());
  // Nor an interleaved stereo one (V4L2's Y8I): its fourcc maps to nothing.
  EXPECT_FALSE(libcameraFormatOf(PixelFormat::kY8i).has_value());
  EXPECT_FALSE(pixelFormatFromLibcamera(libcamera::PixelFormat(fourccOf(PixelFormat::kY8i))));
}

TEST(LibcameraFormat, ParsesCbloxAndLibcameraNames) {
  const std::vector<std::pair<std::string, libcamera::PixelFormat>> cases = {
      {"YUYV", formats::YUYV},     {"yuyv", formats::YUYV},         {"UYVY", formats::UYVY},
      {"NV12", formats::NV12},     {"YUV420", formats::YUV420},     {"I420", formats::YUV420},
      {"GREY", formats::R8},       {"MJPEG", formats::MJPEG},       {"MJPG", formats::MJPEG},
      {"RGB24", formats::BGR888},  // R G B in memory
      {"BGR24", formats::RGB888},  {"XRGB8888", formats::XRGB8888}, {"R8", formats::R8},
      {"RGB888", formats::RGB888},  // libcamera's name
      {"BGR888", formats::BGR888},
  };
  for (const auto& [name, expected] : cases) {
    std::string error;
    const std::optional<libcamera::PixelFormat> parsed = parseLibcameraPixelFormat(name, &error);
    ASSERT_TRUE(parsed.has_value()) << name << ": " << error;
    EXPECT_EQ(*parsed, expected) << name;
  }
}

TEST(LibcameraFormat, RefusesUnknownOrUnconvertibleNames) {
  std::string error;
  EXPECT_FALSE(parseLibcameraPixelFormat("H264", &error).has_value());
  EXPECT_TRUE(contains(error, "'H264' is not a known pixel format name"));
  EXPECT_TRUE(contains(error, "YUYV (libcamera YUYV)"));  // lists what is accepted
  EXPECT_TRUE(contains(error, "BGR24 (libcamera RGB888)"));
  EXPECT_FALSE(parseLibcameraPixelFormat("SRGGB10", &error).has_value());
  EXPECT_TRUE(contains(error, "'SRGGB10' (a libcamera format) cannot be converted"));
  EXPECT_FALSE(parseLibcameraPixelFormat("Y16", &error).has_value());
  EXPECT_TRUE(contains(error, "'Y16' has no libcamera stream format"));
  EXPECT_FALSE(parseLibcameraPixelFormat("Y8I", &error).has_value());
  EXPECT_TRUE(contains(error, "'Y8I' has no libcamera stream format"));
  EXPECT_FALSE(parseLibcameraPixelFormat("", &error).has_value());
  EXPECT_FALSE(parseLibcameraPixelFormat("YUYV ", nullptr).has_value());
}

TEST(LibcameraFormat, DescribesFormats) {
  EXPECT_EQ(describeLibcameraFormat(formats::RGB888), "BGR24 (libcamera RGB888)");
  EXPECT_EQ(describeLibcameraFormat(formats::R8), "GREY (libcamera R8)");
  EXPECT_EQ(describeLibcameraFormat(formats::SRGGB10), "SRGGB10");
}

}  // namespace
}  // namespace cblox
