#include "drivers/pixel/pixel_convert.h"

#include <linux/videodev2.h>
#include <turbojpeg.h>

#include <cmath>
#include <cstdlib>
#include <random>
#include <vector>

#include <gtest/gtest.h>

namespace cblox {
namespace {

// ---- Test patterns and reference encoders (the standard formulas, written independently).

constexpr uint8_t kPad = 0xEE;  // fills row padding; must never show in an output

/// A colour pattern whose 2x2 blocks are uniform (so 4:2:2 and 4:2:0 chroma subsampling
/// loses nothing) and which covers black, white, the primaries and many mixtures.
ColorImage blockPattern(int width, int height) {
  ColorImage image(width, height);
  for (int v = 0; v < height; ++v) {
    for (int u = 0; u < width; ++u) {
      const int bu = u / 2;
      const int bv = v / 2;
      const int i = bv * (width / 2) + bu;
      Color c{static_cast<uint8_t>((i * 37 + bv * 11) % 256),
              static_cast<uint8_t>((i * 91 + 50) % 256),
              static_cast<uint8_t>((i * 53 + bu * 29) % 256)};
      if (i == 0) c = Color{0, 0, 0};
      if (i == 1) c = Color{255, 255, 255};
      if (i == 2) c = Color{255, 0, 0};
      if (i == 3) c = Color{0, 255, 0};
      if (i == 4) c = Color{0, 0, 255};
      image(u, v) = c;
    }
  }
  return image;
}

/// A smooth colour gradient (JPEG-friendly).
ColorImage smoothPattern(int width, int height) {
  ColorImage image(width, height);
  for (int v = 0; v < height; ++v) {
    for (int u = 0; u < width; ++u) {
      image(u, v) = Color{static_cast<uint8_t>(40 + 160 * u / width),
                          static_cast<uint8_t>(30 + 180 * v / height),
                          static_cast<uint8_t>(200 - 100 * (u + v) / (width + height))};
    }
  }
  return image;
}

struct Yuv {
  uint8_t y, u, v;
};

/// BT.601 limited-range RGB -> YCbCr (the common integer approximation).
Yuv rgbToYuv(Color c) {
  const int r = c.r, g = c.g, b = c.b;
  return Yuv{static_cast<uint8_t>(((66 * r + 129 * g + 25 * b + 128) >> 8) + 16),
             static_cast<uint8_t>(((-38 * r - 74 * g + 112 * b + 128) >> 8) + 128),
             static_cast<uint8_t>(((112 * r - 94 * g - 18 * b + 128) >> 8) + 128)};
}

/// BT.601 luma in floating point, rounded.
int referenceLuma(Color c) {
  return static_cast<int>(std::lround(0.299 * c.r + 0.587 * c.g + 0.114 * c.b));
}

/// A buffer of `rows` rows of `stride` bytes, padding filled with kPad.
struct Buffer {
  std::vector<uint8_t> bytes;
  RawImage raw(PixelFormat format, int width, int height, size_t stride) const {
    return RawImage{format, width, height, stride, bytes.data(), bytes.size()};
  }
};

Buffer encodeYuv422(const ColorImage& image, PixelFormat format, size_t stride) {
  Buffer buffer;
  buffer.bytes.assign(stride * static_cast<size_t>(image.height), kPad);
  for (int v = 0; v < image.height; ++v) {
    uint8_t* row = buffer.bytes.data() + static_cast<size_t>(v) * stride;
    for (int u = 0; u < image.width; u += 2) {
      const Yuv a = rgbToYuv(image(u, v));
      const Yuv b = rgbToYuv(image(u + 1, v));
      uint8_t* m = row + 2 * u;
      if (format == PixelFormat::kYuyv) {
        m[0] = a.y, m[1] = a.u, m[2] = b.y, m[3] = a.v;
      } else {
        m[0] = a.u, m[1] = a.y, m[2] = a.v, m[3] = b.y;
      }
    }
  }
  return buffer;
}

Buffer encodeYuv420(const ColorImage& image, PixelFormat format, size_t stride) {
  const auto h = static_cast<size_t>(image.height);
  Buffer buffer;
  buffer.bytes.assign(stride * h + stride * (h / 2), kPad);  // NV12 and YUV420 alike
  for (int v = 0; v < image.height; ++v) {
    for (int u = 0; u < image.width; ++u) {
      buffer.bytes[static_cast<size_t>(v) * stride + static_cast<size_t>(u)] =
          rgbToYuv(image(u, v)).y;
    }
  }
  uint8_t* chroma = buffer.bytes.data() + stride * h;
  for (int v = 0; v < image.height / 2; ++v) {
    for (int u = 0; u < image.width / 2; ++u) {
      const Yuv c = rgbToYuv(image(2 * u, 2 * v));
      if (format == PixelFormat::kNv12) {
        chroma[static_cast<size_t>(v) * stride + 2 * static_cast<size_t>(u)] = c.u;
        chroma[static_cast<size_t>(v) * stride + 2 * static_cast<size_t>(u) + 1] = c.v;
      } else {
        const size_t cs = stride / 2;
        chroma[static_cast<size_t>(v) * cs + static_cast<size_t>(u)] = c.u;
        chroma[cs * h / 2 + static_cast<size_t>(v) * cs + static_cast<size_t>(u)] = c.v;
      }
    }
  }
  return buffer;
}

Buffer encodeRgb(const ColorImage& image, PixelFormat format, size_t stride) {
  Buffer buffer;
  buffer.bytes.assign(stride * static_cast<size_t>(image.height), kPad);
  const int size = format == PixelFormat::kXrgb8888 ? 4 : 3;
  for (int v = 0; v < image.height; ++v) {
    for (int u = 0; u < image.width; ++u) {
      uint8_t* p =
          buffer.bytes.data() + static_cast<size_t>(v) * stride + static_cast<size_t>(u * size);
      const Color c = image(u, v);
      if (format == PixelFormat::kRgb24) {
        p[0] = c.r, p[1] = c.g, p[2] = c.b;
      } else {  // BGR24 and XRGB8888 (B G R X in memory)
        p[0] = c.b, p[1] = c.g, p[2] = c.r;
        if (size == 4) p[3] = 0x7F;
      }
    }
  }
  return buffer;
}

Buffer encode16(const Image<uint16_t>& image, size_t stride) {
  Buffer buffer;
  buffer.bytes.assign(stride * static_cast<size_t>(image.height), kPad);
  for (int v = 0; v < image.height; ++v) {
    for (int u = 0; u < image.width; ++u) {
      uint8_t* p = buffer.bytes.data() + static_cast<size_t>(v) * stride + 2 * u;
      p[0] = static_cast<uint8_t>(image(u, v) & 0xff);
      p[1] = static_cast<uint8_t>(image(u, v) >> 8);
    }
  }
  return buffer;
}

/// Y8I as the kernel documents it (pixfmt-y8i.rst): each pixel a 16-bit word, the left
/// view's byte first, the right's second; padding after each row filled with kPad.
Buffer encodeY8i(const GrayImage& left, const GrayImage& right, size_t stride) {
  Buffer buffer;
  buffer.bytes.assign(stride * static_cast<size_t>(left.height), kPad);
  for (int v = 0; v < left.height; ++v) {
    for (int u = 0; u < left.width; ++u) {
      uint8_t* p = buffer.bytes.data() + static_cast<size_t>(v) * stride + 2 * u;
      p[0] = left(u, v);
      p[1] = right(u, v);
    }
  }
  return buffer;
}

/// Two different grey patterns of one size (no value of one at the same pixel of the other).
GrayImage greyPattern(int width, int height, int seed) {
  GrayImage image(width, height);
  for (int v = 0; v < height; ++v) {
    for (int u = 0; u < width; ++u) {
      image(u, v) = static_cast<uint8_t>((seed * 101 + u * 7 + v * 31 + u * v) % 256);
    }
  }
  return image;
}

std::vector<uint8_t> compressJpeg(const ColorImage& image, int quality, int subsampling) {
  std::vector<uint8_t> rgb;
  for (const Color& c : image.data) rgb.insert(rgb.end(), {c.r, c.g, c.b});
  tjhandle handle = tjInitCompress();
  EXPECT_NE(handle, nullptr);
  unsigned char* jpeg = nullptr;
  unsigned long size = 0;
  EXPECT_EQ(tjCompress2(handle, rgb.data(), image.width, image.width * 3, image.height, TJPF_RGB,
                        &jpeg, &size, subsampling, quality, 0),
            0)
      << tjGetErrorStr2(handle);
  std::vector<uint8_t> out(jpeg, jpeg + size);
  tjFree(jpeg);
  tjDestroy(handle);
  return out;
}

/// Removes every DHT (0xFFC4) segment before the start of scan, as UVC cameras send MJPEG.
std::vector<uint8_t> stripHuffmanTables(const std::vector<uint8_t>& jpeg) {
  std::vector<uint8_t> out(jpeg.begin(), jpeg.begin() + 2);  // SOI
  size_t i = 2;
  while (i + 4 <= jpeg.size()) {
    const uint8_t marker = jpeg[i + 1];
    const size_t length = (static_cast<size_t>(jpeg[i + 2]) << 8) | jpeg[i + 3];
    if (marker == 0xDA) break;  // SOS: the rest is scan data
    if (marker != 0xC4) out.insert(out.end(), jpeg.begin() + i, jpeg.begin() + i + 2 + length);
    i += 2 + length;
  }
  out.insert(out.end(), jpeg.begin() + i, jpeg.end());
  return out;
}

bool hasMarker(const std::vector<uint8_t>& jpeg, uint8_t marker) {
  for (size_t i = 0; i + 1 < jpeg.size(); ++i) {
    if (jpeg[i] == 0xFF && jpeg[i + 1] == marker) return true;
  }
  return false;
}

int maxAbsDifference(const ColorImage& a, const ColorImage& b) {
  int worst = 0;
  for (size_t i = 0; i < a.data.size(); ++i) {
    worst = std::max({worst, std::abs(a.data[i].r - b.data[i].r),
                      std::abs(a.data[i].g - b.data[i].g), std::abs(a.data[i].b - b.data[i].b)});
  }
  return worst;
}

double meanAbsDifference(const ColorImage& a, const ColorImage& b) {
  double sum = 0.0;
  for (size_t i = 0; i < a.data.size(); ++i) {
    sum += std::abs(a.data[i].r - b.data[i].r) + std::abs(a.data[i].g - b.data[i].g) +
           std::abs(a.data[i].b - b.data[i].b);
  }
  return sum / (3.0 * static_cast<double>(a.data.size()));
}

// ---- Formats

TEST(PixelFormatTest, NamesAndFourccsRoundTrip) {
  for (PixelFormat f :
       {PixelFormat::kGrey, PixelFormat::kY16, PixelFormat::kYuyv, PixelFormat::kUyvy,
        PixelFormat::kNv12, PixelFormat::kYuv420, PixelFormat::kRgb24, PixelFormat::kBgr24,
        PixelFormat::kXrgb8888, PixelFormat::kMjpeg, PixelFormat::kZ16, PixelFormat::kY8i}) {
    EXPECT_EQ(pixelFormatFromFourcc(fourccOf(f)), f) << pixelFormatName(f);
    EXPECT_EQ(pixelFormatFromName(pixelFormatName(f)), f) << pixelFormatName(f);
  }
  EXPECT_EQ(pixelFormatName(PixelFormat::kYuyv), "YUYV");
  EXPECT_EQ(pixelFormatName(PixelFormat::kY16), "Y16");
  EXPECT_EQ(fourccOf(PixelFormat::kZ16), V4L2_PIX_FMT_Z16);
  EXPECT_EQ(fourccOf(PixelFormat::kXrgb8888), V4L2_PIX_FMT_XBGR32);
  EXPECT_EQ(fourccToString(V4L2_PIX_FMT_YUYV), "YUYV");
  EXPECT_EQ(fourccToString(V4L2_PIX_FMT_Y16), "Y16 ");
  EXPECT_EQ(fourccToString(0x01020304u), "....");
  EXPECT_EQ(pixelFormatFromFourcc(V4L2_PIX_FMT_JPEG), PixelFormat::kMjpeg);
  EXPECT_EQ(pixelFormatFromFourcc(V4L2_PIX_FMT_H264), std::nullopt);
  EXPECT_EQ(pixelFormatFromName("yuyv"), PixelFormat::kYuyv);
  EXPECT_EQ(pixelFormatFromName("MJPG"), PixelFormat::kMjpeg);
  EXPECT_EQ(pixelFormatFromName("I420"), PixelFormat::kYuv420);
  EXPECT_EQ(pixelFormatFromName("H264"), std::nullopt);
  // Y8I: the RealSense IR pair, 16 bits a pixel.
  EXPECT_EQ(pixelFormatName(PixelFormat::kY8i), "Y8I");
  EXPECT_EQ(fourccOf(PixelFormat::kY8i), V4L2_PIX_FMT_Y8I);
  EXPECT_EQ(fourccToString(V4L2_PIX_FMT_Y8I), "Y8I ");
  EXPECT_EQ(pixelFormatFromName("Y8I"), PixelFormat::kY8i);
  EXPECT_EQ(pixelFormatFromName("Y8I "), PixelFormat::kY8i);
  EXPECT_EQ(pixelFormatFromName("y8i"), PixelFormat::kY8i);
  EXPECT_EQ(pixelFormatFromFourcc(V4L2_PIX_FMT_Y8I), PixelFormat::kY8i);
  EXPECT_EQ(pixelFormatFromFourcc(V4L2_PIX_FMT_Y12I), std::nullopt);
  EXPECT_EQ(minRowBytes(PixelFormat::kY8i, 848), 1696u);
  EXPECT_EQ(minRowBytes(PixelFormat::kY8i, 0), 0u);
}

TEST(PixelFormatTest, DrmFourccsNameRgbByWordOrder) {
  auto drm = [](const char* s) {
    return static_cast<uint32_t>(s[0]) | (static_cast<uint32_t>(s[1]) << 8) |
           (static_cast<uint32_t>(s[2]) << 16) | (static_cast<uint32_t>(s[3]) << 24);
  };
  EXPECT_EQ(pixelFormatFromDrmFourcc(drm("RG24")), PixelFormat::kBgr24);
  EXPECT_EQ(pixelFormatFromDrmFourcc(drm("BG24")), PixelFormat::kRgb24);
  EXPECT_EQ(pixelFormatFromDrmFourcc(drm("XR24")), PixelFormat::kXrgb8888);
  EXPECT_EQ(pixelFormatFromDrmFourcc(drm("R8  ")), PixelFormat::kGrey);
  EXPECT_EQ(pixelFormatFromDrmFourcc(drm("YU12")), PixelFormat::kYuv420);
  EXPECT_EQ(pixelFormatFromDrmFourcc(drm("NV21")), std::nullopt);
  // DRM (and so libcamera) has no interleaved stereo or depth format.
  EXPECT_EQ(pixelFormatFromDrmFourcc(drm("Y8I ")), std::nullopt);
  EXPECT_EQ(pixelFormatFromDrmFourcc(drm("Z16 ")), std::nullopt);
}

TEST(PixelFormatTest, RequiredBytesExemptsOnlyTheLastRowsPadding) {
  EXPECT_EQ(requiredBytes(RawImage{PixelFormat::kYuyv, 4, 3, 16, nullptr, 0}), 16u * 2 + 8);
  EXPECT_EQ(requiredBytes(RawImage{PixelFormat::kYuyv, 4, 3, 0, nullptr, 0}), 24u);
  EXPECT_EQ(requiredBytes(RawImage{PixelFormat::kNv12, 4, 4, 8, nullptr, 0}), 32u + 8 + 4);
  EXPECT_EQ(requiredBytes(RawImage{PixelFormat::kYuv420, 4, 4, 8, nullptr, 0}), 32u + 8 + 4 + 2);
  EXPECT_EQ(requiredBytes(RawImage{PixelFormat::kMjpeg, 4, 4, 0, nullptr, 0}), 0u);
  EXPECT_EQ(requiredBytes(RawImage{PixelFormat::kY8i, 5, 3, 0, nullptr, 0}), 30u);
  EXPECT_EQ(requiredBytes(RawImage{PixelFormat::kY8i, 5, 3, 16, nullptr, 0}), 16u * 2 + 10);
}

// ---- Grey and depth

TEST(PixelConvertTest, GreyWithStrideIsCopiedExactly) {
  const int w = 5, h = 3;
  const size_t stride = 8;
  Buffer buffer;
  buffer.bytes.assign(stride * h, kPad);
  for (int v = 0; v < h; ++v) {
    for (int u = 0; u < w; ++u) buffer.bytes[v * stride + u] = static_cast<uint8_t>(v * 40 + u);
  }
  GrayImage gray;
  ASSERT_TRUE(toGray(buffer.raw(PixelFormat::kGrey, w, h, stride), &gray));
  ASSERT_EQ(gray.width, w);
  ASSERT_EQ(gray.height, h);
  for (int v = 0; v < h; ++v) {
    for (int u = 0; u < w; ++u) EXPECT_EQ(gray(u, v), v * 40 + u);
  }
  ColorImage color;
  ASSERT_TRUE(toColor(buffer.raw(PixelFormat::kGrey, w, h, stride), &color));
  EXPECT_EQ(color(4, 2), (Color{84, 84, 84}));
}

TEST(PixelConvertTest, Y16GivesTheHighByteAndExactDepth) {
  Image<uint16_t> units(6, 4);
  for (int v = 0; v < 4; ++v) {
    for (int u = 0; u < 6; ++u) units(u, v) = static_cast<uint16_t>((v * 6 + u) * 2731);
  }
  const size_t stride = 16;  // 12 bytes of pixels + 4 of padding
  const Buffer buffer = encode16(units, stride);
  GrayImage gray;
  ASSERT_TRUE(toGray(buffer.raw(PixelFormat::kY16, 6, 4, stride), &gray));
  DepthImage depth;
  ASSERT_TRUE(toDepth(buffer.raw(PixelFormat::kY16, 6, 4, stride), 0.5, &depth));
  for (int v = 0; v < 4; ++v) {
    for (int u = 0; u < 6; ++u) {
      EXPECT_EQ(gray(u, v), units(u, v) >> 8);
      EXPECT_EQ(depth(u, v), static_cast<float>(units(u, v) * 0.5));
    }
  }
}

TEST(PixelConvertTest, Z16DepthIsScaledExactlyAndZeroStaysZero) {
  Image<uint16_t> units(4, 2);
  units(0, 0) = 1234;
  units(1, 0) = 0;
  units(2, 0) = 65535;
  units(3, 0) = 1;
  units(0, 1) = 1000;
  const Buffer buffer = encode16(units, 8);
  DepthImage depth;
  const ConvertResult result = toDepth(buffer.raw(PixelFormat::kZ16, 4, 2, 0), 0.001, &depth);
  ASSERT_TRUE(result) << result.message;
  EXPECT_EQ(depth(0, 0), 1.234f);
  EXPECT_EQ(depth(1, 0), 0.0f);
  EXPECT_EQ(depth(2, 0), 65.535f);
  EXPECT_EQ(depth(3, 0), 0.001f);
  EXPECT_EQ(depth(0, 1), 1.0f);
  EXPECT_EQ(depth(1, 1), 0.0f);
}

TEST(PixelConvertTest, DepthNeedsADepthFormatAndAPositiveScale) {
  const Buffer buffer = encode16(Image<uint16_t>(2, 2, 7), 4);
  DepthImage depth(1, 1, 9.0f);
  EXPECT_EQ(toDepth(buffer.raw(PixelFormat::kYuyv, 2, 2, 0), 0.001, &depth).error,
            ConvertError::kUnsupported);
  const ConvertResult zero = toDepth(buffer.raw(PixelFormat::kZ16, 2, 2, 0), 0.0, &depth);
  EXPECT_EQ(zero.error, ConvertError::kUnsupported);
  EXPECT_NE(zero.message.find("metres per depth unit"), std::string::npos) << zero.message;
  EXPECT_EQ(toDepth(buffer.raw(PixelFormat::kZ16, 2, 2, 0), NAN, &depth).error,
            ConvertError::kUnsupported);
  EXPECT_EQ(depth.width, 1);  // untouched
  GrayImage gray;
  EXPECT_EQ(toGray(buffer.raw(PixelFormat::kZ16, 2, 2, 0), &gray).error,
            ConvertError::kUnsupported);
}

// ---- YUV

TEST(PixelConvertTest, YuvLimitedRangeEndpointsAreExact) {
  // Y U Y V: black (16, 128, 128) and white (235, 128, 128).
  const std::vector<uint8_t> bytes = {16, 128, 235, 128};
  ColorImage color;
  ASSERT_TRUE(toColor(RawImage{PixelFormat::kYuyv, 2, 1, 0, bytes.data(), bytes.size()}, &color));
  EXPECT_EQ(color(0, 0), (Color{0, 0, 0}));
  EXPECT_EQ(color(1, 0), (Color{255, 255, 255}));
  // Below black and above white clamp.
  const std::vector<uint8_t> outside = {0, 255, 255, 255};
  ASSERT_TRUE(
      toColor(RawImage{PixelFormat::kYuyv, 2, 1, 0, outside.data(), outside.size()}, &color));
  EXPECT_EQ(color(0, 0).g, 0);
  EXPECT_EQ(color(1, 0).r, 255);
  EXPECT_EQ(color(1, 0).b, 255);
}

void expectYuvRoundTrip(PixelFormat format, const Buffer& buffer, const ColorImage& pattern,
                        size_t stride) {
  SCOPED_TRACE(std::string(pixelFormatName(format)) + " stride " + std::to_string(stride));
  const RawImage raw = buffer.raw(format, pattern.width, pattern.height, stride);
  ColorImage color;
  const ConvertResult result = toColor(raw, &color);
  ASSERT_TRUE(result) << result.message;
  ASSERT_TRUE(color.sameSize(pattern));
  EXPECT_LE(maxAbsDifference(color, pattern), 2);
  GrayImage gray;
  ASSERT_TRUE(toGray(raw, &gray));
  for (int v = 0; v < pattern.height; ++v) {
    for (int u = 0; u < pattern.width; ++u) {
      ASSERT_EQ(gray(u, v), rgbToYuv(pattern(u, v)).y) << u << "," << v;
    }
  }
}

TEST(PixelConvertTest, Yuv422RoundTripsWithinRounding) {
  const ColorImage pattern = blockPattern(32, 16);
  for (PixelFormat format : {PixelFormat::kYuyv, PixelFormat::kUyvy}) {
    for (size_t stride : {size_t{0}, size_t{64}, size_t{80}}) {
      const Buffer buffer = encodeYuv422(pattern, format, stride == 0 ? 64 : stride);
      expectYuvRoundTrip(format, buffer, pattern, stride);
    }
  }
}

TEST(PixelConvertTest, Yuv420RoundTripsWithinRounding) {
  const ColorImage pattern = blockPattern(32, 16);
  for (PixelFormat format : {PixelFormat::kNv12, PixelFormat::kYuv420}) {
    for (size_t stride : {size_t{0}, size_t{48}}) {
      const Buffer buffer = encodeYuv420(pattern, format, stride == 0 ? 32 : stride);
      expectYuvRoundTrip(format, buffer, pattern, stride);
    }
  }
}

TEST(PixelConvertTest, Yuv422SharesChromaBetweenPairs) {
  // Two pixels of different luma, one chroma pair: pure red's chroma.
  const Yuv red = rgbToYuv(Color{255, 0, 0});
  const std::vector<uint8_t> uyvy = {red.u, red.y, red.v, 16};
  ColorImage color;
  ASSERT_TRUE(toColor(RawImage{PixelFormat::kUyvy, 2, 1, 0, uyvy.data(), uyvy.size()}, &color));
  EXPECT_LE(maxAbsDifference(ColorImage(1, 1, color(0, 0)), ColorImage(1, 1, Color{255, 0, 0})), 2);
  EXPECT_LT(color(1, 0).r, color(0, 0).r);
}

// ---- RGB

TEST(PixelConvertTest, RgbFormatsAreExactAndGreyIsBt601Luma) {
  const ColorImage pattern = blockPattern(10, 6);
  for (PixelFormat format : {PixelFormat::kRgb24, PixelFormat::kBgr24, PixelFormat::kXrgb8888}) {
    SCOPED_TRACE(std::string(pixelFormatName(format)));
    const size_t stride = minRowBytes(format, 10) + 7;
    const Buffer buffer = encodeRgb(pattern, format, stride);
    ColorImage color;
    ASSERT_TRUE(toColor(buffer.raw(format, 10, 6, stride), &color));
    EXPECT_EQ(color.data, pattern.data);
    GrayImage gray;
    ASSERT_TRUE(toGray(buffer.raw(format, 10, 6, stride), &gray));
    for (size_t i = 0; i < gray.data.size(); ++i) {
      EXPECT_NEAR(gray.data[i], referenceLuma(pattern.data[i]), 1) << pattern.data[i];
    }
    EXPECT_EQ(gray(0, 0), 0);    // black
    EXPECT_EQ(gray(2, 0), 255);  // white
  }
}

// ---- MJPEG

TEST(PixelConvertTest, MjpegDecodesWithinJpegTolerance) {
  const ColorImage pattern = smoothPattern(64, 48);
  for (int subsampling : {TJSAMP_444, TJSAMP_422, TJSAMP_420}) {
    SCOPED_TRACE(subsampling);
    const std::vector<uint8_t> jpeg = compressJpeg(pattern, 95, subsampling);
    const RawImage raw{PixelFormat::kMjpeg, 64, 48, 0, jpeg.data(), jpeg.size()};
    ColorImage color;
    const ConvertResult result = toColor(raw, &color);
    ASSERT_TRUE(result) << result.message;
    ASSERT_TRUE(color.sameSize(pattern));
    EXPECT_LT(meanAbsDifference(color, pattern), 3.0);
    GrayImage gray;
    ASSERT_TRUE(toGray(raw, &gray));
    double error = 0.0;
    for (size_t i = 0; i < gray.data.size(); ++i) {
      error += std::abs(gray.data[i] - referenceLuma(pattern.data[i]));
    }
    EXPECT_LT(error / static_cast<double>(gray.data.size()), 3.0);
  }
}

TEST(PixelConvertTest, MjpegWithoutHuffmanTablesUsesTheStandardOnes) {
  const ColorImage pattern = smoothPattern(64, 48);
  const std::vector<uint8_t> jpeg = compressJpeg(pattern, 90, TJSAMP_422);
  const std::vector<uint8_t> bare = stripHuffmanTables(jpeg);
  ASSERT_TRUE(hasMarker(jpeg, 0xC4));
  ASSERT_FALSE(hasMarker(bare, 0xC4));
  ASSERT_LT(bare.size(), jpeg.size());
  ColorImage with_tables, without_tables;
  ASSERT_TRUE(
      toColor(RawImage{PixelFormat::kMjpeg, 64, 48, 0, jpeg.data(), jpeg.size()}, &with_tables));
  const ConvertResult result =
      toColor(RawImage{PixelFormat::kMjpeg, 64, 48, 0, bare.data(), bare.size()}, &without_tables);
  ASSERT_TRUE(result) << result.message;
  EXPECT_EQ(with_tables.data, without_tables.data);
}

TEST(PixelConvertTest, CorruptMjpegFailsWithLibjpegsMessage) {
  const ColorImage pattern = smoothPattern(64, 48);
  const std::vector<uint8_t> jpeg = compressJpeg(pattern, 90, TJSAMP_420);
  ColorImage color(1, 1, Color{1, 2, 3});
  GrayImage gray(1, 1, 5);

  const std::vector<uint8_t> truncated(jpeg.begin(), jpeg.begin() + jpeg.size() / 2);
  ConvertResult result =
      toColor(RawImage{PixelFormat::kMjpeg, 64, 48, 0, truncated.data(), truncated.size()}, &color);
  EXPECT_EQ(result.error, ConvertError::kDecodeFailed);
  EXPECT_NE(result.message.find("MJPEG 64x48"), std::string::npos) << result.message;
  EXPECT_EQ(
      toGray(RawImage{PixelFormat::kMjpeg, 64, 48, 0, truncated.data(), truncated.size()}, &gray)
          .error,
      ConvertError::kDecodeFailed);

  std::mt19937 rng(7);
  std::vector<uint8_t> garbage(2000);
  for (uint8_t& b : garbage) b = static_cast<uint8_t>(rng());
  result =
      toColor(RawImage{PixelFormat::kMjpeg, 64, 48, 0, garbage.data(), garbage.size()}, &color);
  EXPECT_EQ(result.error, ConvertError::kDecodeFailed);
  EXPECT_NE(result.message.find("bad JPEG header"), std::string::npos) << result.message;

  // Valid header, scan data overwritten with garbage.
  std::vector<uint8_t> scrambled = jpeg;
  for (size_t i = scrambled.size() / 2; i + 2 < scrambled.size(); ++i) {
    scrambled[i] = static_cast<uint8_t>(rng());
  }
  result =
      toColor(RawImage{PixelFormat::kMjpeg, 64, 48, 0, scrambled.data(), scrambled.size()}, &color);
  EXPECT_EQ(result.error, ConvertError::kDecodeFailed) << result.message;

  result = toColor(RawImage{PixelFormat::kMjpeg, 32, 48, 0, jpeg.data(), jpeg.size()}, &color);
  EXPECT_EQ(result.error, ConvertError::kDecodeFailed);
  EXPECT_NE(result.message.find("JPEG stream is 64x48, not the announced size"), std::string::npos)
      << result.message;

  EXPECT_EQ(toColor(RawImage{PixelFormat::kMjpeg, 64, 48, 0, jpeg.data(), 0}, &color).error,
            ConvertError::kShortBuffer);
  EXPECT_EQ(color.width, 1);  // untouched by every failure
  EXPECT_EQ(color(0, 0), (Color{1, 2, 3}));
  EXPECT_EQ(gray.width, 1);
}

// ---- Bounds

TEST(PixelConvertTest, BadLayoutsFailBeforeReadingAPixel) {
  const std::vector<uint8_t> bytes(64 * 48 * 2, 100);
  GrayImage gray(1, 1, 5);
  ColorImage color;

  ConvertResult result =
      toGray(RawImage{PixelFormat::kYuyv, 64, 48, 0, bytes.data(), bytes.size() - 1}, &gray);
  EXPECT_EQ(result.error, ConvertError::kShortBuffer);
  EXPECT_EQ(result.message, "YUYV 64x48: buffer holds 6143 bytes, needs 6144");
  EXPECT_EQ(convertErrorName(result.error), "short_buffer");

  result = toGray(RawImage{PixelFormat::kYuyv, 64, 48, 0, nullptr, bytes.size()}, &gray);
  EXPECT_EQ(result.error, ConvertError::kShortBuffer);

  result = toGray(RawImage{PixelFormat::kGrey, 0, 48, 0, bytes.data(), bytes.size()}, &gray);
  EXPECT_EQ(result.error, ConvertError::kBadSize);
  result = toGray(RawImage{PixelFormat::kGrey, 64, -1, 0, bytes.data(), bytes.size()}, &gray);
  EXPECT_EQ(result.error, ConvertError::kBadSize);
  result = toGray(RawImage{PixelFormat::kGrey, 20000, 1, 0, bytes.data(), bytes.size()}, &gray);
  EXPECT_EQ(result.error, ConvertError::kBadSize);

  result = toColor(RawImage{PixelFormat::kYuyv, 63, 48, 0, bytes.data(), bytes.size()}, &color);
  EXPECT_EQ(result.error, ConvertError::kBadSize);
  EXPECT_EQ(result.message, "YUYV 63x48: width must be even for 4:2:2");
  result = toColor(RawImage{PixelFormat::kNv12, 64, 47, 0, bytes.data(), bytes.size()}, &color);
  EXPECT_EQ(result.error, ConvertError::kBadSize);

  result = toGray(RawImage{PixelFormat::kRgb24, 16, 4, 47, bytes.data(), bytes.size()}, &gray);
  EXPECT_EQ(result.error, ConvertError::kBadStride);
  EXPECT_EQ(result.message, "RGB24 16x4: stride 47 is less than a row of 48 bytes");
  result = toGray(RawImage{PixelFormat::kGrey, 16, 4, size_t{1} << 40, bytes.data(), bytes.size()},
                  &gray);
  EXPECT_EQ(result.error, ConvertError::kBadStride);

  // A stride that pushes the last row past the end of the buffer.
  result = toGray(RawImage{PixelFormat::kGrey, 16, 48, 160, bytes.data(), bytes.size()}, &gray);
  EXPECT_EQ(result.error, ConvertError::kShortBuffer);
  // NV12 whose chroma plane is missing.
  result = toColor(RawImage{PixelFormat::kNv12, 64, 48, 0, bytes.data(), 64 * 48}, &color);
  EXPECT_EQ(result.error, ConvertError::kShortBuffer);

  EXPECT_EQ(gray.width, 1);  // untouched
  EXPECT_EQ(gray(0, 0), 5);
  EXPECT_TRUE(color.empty());
}

// ---- Side by side

TEST(PixelConvertTest, SideBySideSplitsExactly) {
  GrayImage both(8, 3);
  for (int v = 0; v < 3; ++v) {
    for (int u = 0; u < 8; ++u) both(u, v) = static_cast<uint8_t>(10 * v + u);
  }
  GrayImage left, right;
  ASSERT_TRUE(splitSideBySide(both, &left, &right));
  ASSERT_EQ(left.width, 4);
  ASSERT_EQ(right.width, 4);
  ASSERT_EQ(left.height, 3);
  for (int v = 0; v < 3; ++v) {
    for (int u = 0; u < 4; ++u) {
      EXPECT_EQ(left(u, v), 10 * v + u);
      EXPECT_EQ(right(u, v), 10 * v + u + 4);
    }
  }
}

TEST(PixelConvertTest, SideBySideRejectsOddAndEmptyFrames) {
  GrayImage left(1, 1, 9), right;
  ConvertResult result = splitSideBySide(GrayImage(7, 2), &left, &right);
  EXPECT_EQ(result.error, ConvertError::kBadSize);
  EXPECT_EQ(result.message, "side-by-side frame 7x2: width must be even");
  EXPECT_EQ(splitSideBySide(GrayImage(), &left, &right).error, ConvertError::kBadSize);
  GrayImage inconsistent(8, 2);
  inconsistent.data.resize(10);
  EXPECT_EQ(splitSideBySide(inconsistent, &left, &right).error, ConvertError::kShortBuffer);
  EXPECT_EQ(left(0, 0), 9);  // untouched
}

// ---- Interleaved stereo (Y8I)

TEST(PixelConvertTest, Y8iByteOrderIsLeftThenRight) {
  // The kernel's table: start + 0: Y'00left Y'00right Y'01left Y'01right ...
  const std::vector<uint8_t> bytes = {10, 20, 11, 21, 12, 22, 13, 23, 14, 24, 15, 25};
  GrayImage left, right;
  const ConvertResult result = splitInterleaved(
      RawImage{PixelFormat::kY8i, 3, 2, 0, bytes.data(), bytes.size()}, &left, &right);
  ASSERT_TRUE(result) << result.message;
  EXPECT_EQ(left.width, 3);
  EXPECT_EQ(left.height, 2);
  EXPECT_EQ(left.data, (std::vector<uint8_t>{10, 11, 12, 13, 14, 15}));
  EXPECT_EQ(right.data, (std::vector<uint8_t>{20, 21, 22, 23, 24, 25}));
}

TEST(PixelConvertTest, Y8iSplitsBackToBothPatternsExactly) {
  // An odd width: Y8I has no halves, each view is as wide as the frame.
  const int w = 7, h = 5;
  const GrayImage left_pattern = greyPattern(w, h, 1);
  const GrayImage right_pattern = greyPattern(w, h, 2);
  ASSERT_NE(left_pattern.data, right_pattern.data);
  for (size_t stride : {size_t{0}, size_t{14}, size_t{20}, size_t{64}}) {
    SCOPED_TRACE("stride " + std::to_string(stride));
    const Buffer buffer = encodeY8i(left_pattern, right_pattern, stride == 0 ? 14 : stride);
    GrayImage left, right;
    const ConvertResult result =
        splitInterleaved(buffer.raw(PixelFormat::kY8i, w, h, stride), &left, &right);
    ASSERT_TRUE(result) << result.message;
    ASSERT_TRUE(left.sameSize(left_pattern));
    ASSERT_TRUE(right.sameSize(right_pattern));
    EXPECT_EQ(left.data, left_pattern.data);
    EXPECT_EQ(right.data, right_pattern.data);
  }
  // A buffer cut just after the last row's pixels (no padding after it) is enough.
  Buffer exact = encodeY8i(left_pattern, right_pattern, 20);
  exact.bytes.resize(20 * (h - 1) + 2 * w);
  GrayImage left, right;
  ASSERT_TRUE(splitInterleaved(exact.raw(PixelFormat::kY8i, w, h, 20), &left, &right));
  EXPECT_EQ(left.data, left_pattern.data);
  EXPECT_EQ(right.data, right_pattern.data);
}

TEST(PixelConvertTest, Y8iBadLayoutsFailAndLeaveTheOutputsAlone) {
  const int w = 7, h = 5;
  const Buffer buffer = encodeY8i(greyPattern(w, h, 1), greyPattern(w, h, 2), 16);
  GrayImage left(1, 1, 9), right(2, 1, 8);

  ConvertResult result = splitInterleaved(
      RawImage{PixelFormat::kY8i, w, h, 16, buffer.bytes.data(), 16 * (h - 1) + 2 * w - 1}, &left,
      &right);
  EXPECT_EQ(result.error, ConvertError::kShortBuffer);
  EXPECT_EQ(result.message, "Y8I 7x5: buffer holds 77 bytes, needs 78");
  result = splitInterleaved(RawImage{PixelFormat::kY8i, w, h, 16, nullptr, buffer.bytes.size()},
                            &left, &right);
  EXPECT_EQ(result.error, ConvertError::kShortBuffer);

  result = splitInterleaved(buffer.raw(PixelFormat::kY8i, 0, h, 16), &left, &right);
  EXPECT_EQ(result.error, ConvertError::kBadSize);
  EXPECT_EQ(result.message, "Y8I 0x5: size must be within 1..16384 per side");
  EXPECT_EQ(splitInterleaved(buffer.raw(PixelFormat::kY8i, w, 0, 16), &left, &right).error,
            ConvertError::kBadSize);
  EXPECT_EQ(splitInterleaved(buffer.raw(PixelFormat::kY8i, w, -3, 16), &left, &right).error,
            ConvertError::kBadSize);
  EXPECT_EQ(splitInterleaved(buffer.raw(PixelFormat::kY8i, 20000, 1, 0), &left, &right).error,
            ConvertError::kBadSize);

  // A stride of one view's width (W bytes, not 2W) is the classic mistake.
  result = splitInterleaved(buffer.raw(PixelFormat::kY8i, w, h, 13), &left, &right);
  EXPECT_EQ(result.error, ConvertError::kBadStride);
  EXPECT_EQ(result.message, "Y8I 7x5: stride 13 is less than a row of 14 bytes");
  EXPECT_EQ(
      splitInterleaved(buffer.raw(PixelFormat::kY8i, w, h, size_t{1} << 40), &left, &right).error,
      ConvertError::kBadStride);
  // A stride that pushes the last row past the end of the buffer.
  EXPECT_EQ(splitInterleaved(buffer.raw(PixelFormat::kY8i, w, h, 32), &left, &right).error,
            ConvertError::kShortBuffer);

  // Only Y8I is interleaved.
  result = splitInterleaved(buffer.raw(PixelFormat::kYuyv, 8, h, 16), &left, &right);
  EXPECT_EQ(result.error, ConvertError::kUnsupported);
  EXPECT_EQ(result.message,
            "YUYV 8x5: cannot split YUYV into a stereo pair: only Y8I is interleaved stereo");

  EXPECT_EQ(left.width, 1);  // untouched by every failure
  EXPECT_EQ(left(0, 0), 9);
  EXPECT_EQ(right.width, 2);
  EXPECT_EQ(right(1, 0), 8);
}

TEST(PixelConvertTest, Y8iIsNotOneImage) {
  const Buffer buffer = encodeY8i(greyPattern(4, 2, 1), greyPattern(4, 2, 2), 8);
  const RawImage raw = buffer.raw(PixelFormat::kY8i, 4, 2, 0);
  GrayImage gray(1, 1, 5);
  ConvertResult result = toGray(raw, &gray);
  EXPECT_EQ(result.error, ConvertError::kUnsupported);
  EXPECT_EQ(result.message,
            "Y8I 4x2: cannot convert Y8I to grey: it is interleaved stereo (left and right in "
            "one frame); use mode side_by_side");
  ColorImage color;
  result = toColor(raw, &color);
  EXPECT_EQ(result.error, ConvertError::kUnsupported);
  EXPECT_NE(result.message.find("use mode side_by_side"), std::string::npos) << result.message;
  DepthImage depth;
  EXPECT_EQ(toDepth(raw, 0.001, &depth).error, ConvertError::kUnsupported);
  EXPECT_EQ(gray.width, 1);  // untouched
  EXPECT_EQ(gray(0, 0), 5);
  EXPECT_TRUE(color.empty());
  EXPECT_TRUE(depth.empty());
}

}  // namespace
}  // namespace cblox
