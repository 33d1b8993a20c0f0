#include "drivers/pixel/pixel_convert.h"

#include <algorithm>
#include <cmath>
#include <string>
#include <vector>

#include "drivers/pixel/mjpeg_decode.h"

namespace cblox {
namespace {

std::string describe(const RawImage& raw) {
  return std::string(pixelFormatName(raw.format)) + " " + std::to_string(raw.width) + "x" +
         std::to_string(raw.height);
}

ConvertResult unsupported(const RawImage& raw, const std::string& target) {
  return ConvertResult{ConvertError::kUnsupported, describe(raw) + ": cannot convert " +
                                                       std::string(pixelFormatName(raw.format)) +
                                                       " to " + target};
}

/// kY8i carries two views: neither toGray() nor toColor() can make one image of it.
ConvertResult interleavedStereo(const RawImage& raw, const std::string& target) {
  return ConvertResult{ConvertError::kUnsupported,
                       describe(raw) + ": cannot convert " +
                           std::string(pixelFormatName(raw.format)) + " to " + target +
                           ": it is interleaved stereo (left and right in one frame); use mode "
                           "side_by_side"};
}

/// First byte of row v of the first plane.
const uint8_t* row(const RawImage& raw, int v) {
  return raw.data + static_cast<size_t>(v) * effectiveStride(raw);
}

/// The chroma planes of a 4:2:0 frame (checked by checkRawImage): NV12 has one interleaved
/// U V plane (u == the plane, v == u + 1, step 2); YUV420 separate U and V planes (step 1).
struct ChromaPlanes {
  const uint8_t* u = nullptr;
  const uint8_t* v = nullptr;
  size_t stride = 0;
  int step = 1;
};

ChromaPlanes chromaPlanes(const RawImage& raw) {
  const size_t stride = effectiveStride(raw);
  const uint8_t* first = raw.data + stride * static_cast<size_t>(raw.height);
  if (raw.format == PixelFormat::kNv12) return {first, first + 1, stride, 2};
  const size_t chroma_stride = stride / 2;
  return {first, first + chroma_stride * static_cast<size_t>(raw.height / 2), chroma_stride, 1};
}

uint8_t clampByte(int value) { return static_cast<uint8_t>(std::clamp(value, 0, 255)); }

/// BT.601 limited range YCbCr -> RGB, integer form.
Color yuvToRgb(int y, int u, int v) {
  const int c = 298 * (y - 16) + 128;
  const int d = u - 128;
  const int e = v - 128;
  return Color{clampByte((c + 409 * e) >> 8), clampByte((c - 100 * d - 208 * e) >> 8),
               clampByte((c + 516 * d) >> 8)};
}

/// BT.601 luma of a full-range RGB pixel.
uint8_t luma(int r, int g, int b) {
  return static_cast<uint8_t>((77 * r + 150 * g + 29 * b + 128) >> 8);
}

/// Byte offsets of R, G, B within a pixel of an RGB format, and the pixel size.
struct RgbLayout {
  int r, g, b, size;
};

RgbLayout rgbLayout(PixelFormat format) {
  switch (format) {
    case PixelFormat::kRgb24:
      return {0, 1, 2, 3};
    case PixelFormat::kBgr24:
      return {2, 1, 0, 3};
    default:
      return {2, 1, 0, 4};  // kXrgb8888: B G R X
  }
}

bool isRgb(PixelFormat format) {
  return format == PixelFormat::kRgb24 || format == PixelFormat::kBgr24 ||
         format == PixelFormat::kXrgb8888;
}

/// Offsets of Y0, U, Y1, V in a 4-byte 4:2:2 macropixel.
struct Yuv422Layout {
  int y0, u, y1, v;
};

Yuv422Layout yuv422Layout(PixelFormat format) {
  return format == PixelFormat::kYuyv ? Yuv422Layout{0, 1, 2, 3} : Yuv422Layout{1, 0, 3, 2};
}

void grayFromGray(const RawImage& raw, GrayImage* out) {
  for (int v = 0; v < raw.height; ++v) {
    std::copy_n(row(raw, v), raw.width,
                out->data.begin() + static_cast<std::ptrdiff_t>(v) * raw.width);
  }
}

void grayFromY16(const RawImage& raw, GrayImage* out) {
  for (int v = 0; v < raw.height; ++v) {
    const uint8_t* in = row(raw, v);
    for (int u = 0; u < raw.width; ++u) (*out)(u, v) = in[2 * u + 1];
  }
}

void grayFromYuv422(const RawImage& raw, GrayImage* out) {
  const Yuv422Layout layout = yuv422Layout(raw.format);
  for (int v = 0; v < raw.height; ++v) {
    const uint8_t* in = row(raw, v);
    for (int u = 0; u < raw.width; u += 2) {
      const uint8_t* macro = in + 2 * u;
      (*out)(u, v) = macro[layout.y0];
      (*out)(u + 1, v) = macro[layout.y1];
    }
  }
}

void grayFromRgb(const RawImage& raw, GrayImage* out) {
  const RgbLayout layout = rgbLayout(raw.format);
  for (int v = 0; v < raw.height; ++v) {
    const uint8_t* in = row(raw, v);
    for (int u = 0; u < raw.width; ++u) {
      const uint8_t* p = in + static_cast<ptrdiff_t>(u) * layout.size;
      (*out)(u, v) = luma(p[layout.r], p[layout.g], p[layout.b]);
    }
  }
}

void colorFromYuv422(const RawImage& raw, ColorImage* out) {
  const Yuv422Layout layout = yuv422Layout(raw.format);
  for (int v = 0; v < raw.height; ++v) {
    const uint8_t* in = row(raw, v);
    for (int u = 0; u < raw.width; u += 2) {
      const uint8_t* macro = in + 2 * u;
      (*out)(u, v) = yuvToRgb(macro[layout.y0], macro[layout.u], macro[layout.v]);
      (*out)(u + 1, v) = yuvToRgb(macro[layout.y1], macro[layout.u], macro[layout.v]);
    }
  }
}

void colorFromYuv420(const RawImage& raw, ColorImage* out) {
  const ChromaPlanes chroma = chromaPlanes(raw);
  for (int v = 0; v < raw.height; ++v) {
    const uint8_t* y = row(raw, v);
    const size_t chroma_row = static_cast<size_t>(v / 2) * chroma.stride;
    const uint8_t* cu = chroma.u + chroma_row;
    const uint8_t* cv = chroma.v + chroma_row;
    for (int u = 0; u < raw.width; ++u) {
      const size_t c = static_cast<size_t>(u / 2) * static_cast<size_t>(chroma.step);
      (*out)(u, v) = yuvToRgb(y[u], cu[c], cv[c]);
    }
  }
}

void colorFromRgb(const RawImage& raw, ColorImage* out) {
  const RgbLayout layout = rgbLayout(raw.format);
  for (int v = 0; v < raw.height; ++v) {
    const uint8_t* in = row(raw, v);
    for (int u = 0; u < raw.width; ++u) {
      const uint8_t* p = in + static_cast<ptrdiff_t>(u) * layout.size;
      (*out)(u, v) = Color{p[layout.r], p[layout.g], p[layout.b]};
    }
  }
}

void colorFromGray(const RawImage& raw, ColorImage* out) {
  const int size = raw.format == PixelFormat::kY16 ? 2 : 1;
  const int offset = size - 1;  // Y16: the high byte
  for (int v = 0; v < raw.height; ++v) {
    const uint8_t* in = row(raw, v);
    for (int u = 0; u < raw.width; ++u) {
      const uint8_t g = in[u * size + offset];
      (*out)(u, v) = Color{g, g, g};
    }
  }
}

}  // namespace

ConvertResult toGray(const RawImage& raw, GrayImage* out) {
  if (ConvertResult check = checkRawImage(raw); !check) return check;
  if (raw.format == PixelFormat::kZ16) return unsupported(raw, "grey");
  if (raw.format == PixelFormat::kY8i) return interleavedStereo(raw, "grey");
  if (raw.format == PixelFormat::kMjpeg) {
    std::vector<uint8_t> pixels;
    if (ConvertResult decoded = decodeMjpeg(raw, JpegOutput::kGray, &pixels); !decoded) {
      return decoded;
    }
    out->width = raw.width;
    out->height = raw.height;
    out->data = std::move(pixels);
    return {};
  }
  GrayImage gray(raw.width, raw.height);
  switch (raw.format) {
    case PixelFormat::kGrey:
    case PixelFormat::kNv12:
    case PixelFormat::kYuv420:
      grayFromGray(raw, &gray);  // the Y plane comes first
      break;
    case PixelFormat::kY16:
      grayFromY16(raw, &gray);
      break;
    case PixelFormat::kYuyv:
    case PixelFormat::kUyvy:
      grayFromYuv422(raw, &gray);
      break;
    case PixelFormat::kRgb24:
    case PixelFormat::kBgr24:
    case PixelFormat::kXrgb8888:
      grayFromRgb(raw, &gray);
      break;
    case PixelFormat::kMjpeg:
    case PixelFormat::kZ16:
    case PixelFormat::kY8i:
      break;  // handled above
  }
  *out = std::move(gray);
  return {};
}

ConvertResult toColor(const RawImage& raw, ColorImage* out) {
  if (ConvertResult check = checkRawImage(raw); !check) return check;
  if (raw.format == PixelFormat::kZ16) return unsupported(raw, "colour");
  if (raw.format == PixelFormat::kY8i) return interleavedStereo(raw, "colour");
  if (raw.format == PixelFormat::kMjpeg) {
    std::vector<uint8_t> pixels;
    if (ConvertResult decoded = decodeMjpeg(raw, JpegOutput::kRgb, &pixels); !decoded) {
      return decoded;
    }
    ColorImage color(raw.width, raw.height);
    for (size_t i = 0; i < color.data.size(); ++i) {
      color.data[i] = Color{pixels[3 * i], pixels[3 * i + 1], pixels[3 * i + 2]};
    }
    *out = std::move(color);
    return {};
  }
  ColorImage color(raw.width, raw.height);
  if (raw.format == PixelFormat::kYuyv || raw.format == PixelFormat::kUyvy) {
    colorFromYuv422(raw, &color);
  } else if (raw.format == PixelFormat::kNv12 || raw.format == PixelFormat::kYuv420) {
    colorFromYuv420(raw, &color);
  } else if (isRgb(raw.format)) {
    colorFromRgb(raw, &color);
  } else {  // kGrey, kY16
    colorFromGray(raw, &color);
  }
  *out = std::move(color);
  return {};
}

ConvertResult toDepth(const RawImage& raw, double metres_per_unit, DepthImage* out) {
  if (raw.format != PixelFormat::kZ16 && raw.format != PixelFormat::kY16) {
    return unsupported(raw, "depth");
  }
  if (!std::isfinite(metres_per_unit) || metres_per_unit <= 0.0) {
    return ConvertResult{ConvertError::kUnsupported,
                         describe(raw) + ": metres per depth unit must be finite and > 0, got " +
                             std::to_string(metres_per_unit)};
  }
  if (ConvertResult check = checkRawImage(raw); !check) return check;
  DepthImage depth(raw.width, raw.height);
  for (int v = 0; v < raw.height; ++v) {
    const uint8_t* in = row(raw, v);
    for (int u = 0; u < raw.width; ++u) {
      const int units = in[2 * u] | (in[2 * u + 1] << 8);
      depth(u, v) = static_cast<float>(units * metres_per_unit);  // 0 stays 0
    }
  }
  *out = std::move(depth);
  return {};
}

ConvertResult splitSideBySide(const GrayImage& both, GrayImage* left, GrayImage* right) {
  const std::string size = std::to_string(both.width) + "x" + std::to_string(both.height);
  if (both.width <= 0 || both.height <= 0) {
    return ConvertResult{ConvertError::kBadSize, "side-by-side frame " + size + " is empty"};
  }
  if (both.width % 2 != 0) {
    return ConvertResult{ConvertError::kBadSize,
                         "side-by-side frame " + size + ": width must be even"};
  }
  const size_t pixels = static_cast<size_t>(both.width) * static_cast<size_t>(both.height);
  if (both.data.size() < pixels) {
    return ConvertResult{ConvertError::kShortBuffer, "side-by-side frame " + size + ": holds " +
                                                         std::to_string(both.data.size()) +
                                                         " pixels, needs " +
                                                         std::to_string(pixels)};
  }
  const int half = both.width / 2;
  GrayImage l(half, both.height);
  GrayImage r(half, both.height);
  for (int v = 0; v < both.height; ++v) {
    const auto in = both.data.begin() + static_cast<std::ptrdiff_t>(v) * both.width;
    const auto offset = static_cast<std::ptrdiff_t>(v) * half;
    std::copy_n(in, half, l.data.begin() + offset);
    std::copy_n(in + half, half, r.data.begin() + offset);
  }
  *left = std::move(l);
  *right = std::move(r);
  return {};
}

ConvertResult splitInterleaved(const RawImage& raw, GrayImage* left, GrayImage* right) {
  if (raw.format != PixelFormat::kY8i) {
    return ConvertResult{ConvertError::kUnsupported,
                         describe(raw) + ": cannot split " +
                             std::string(pixelFormatName(raw.format)) +
                             " into a stereo pair: only Y8I is interleaved stereo"};
  }
  if (ConvertResult check = checkRawImage(raw); !check) return check;
  GrayImage l(raw.width, raw.height);
  GrayImage r(raw.width, raw.height);
  for (int v = 0; v < raw.height; ++v) {
    const uint8_t* in = row(raw, v);
    for (int u = 0; u < raw.width; ++u) {
      l(u, v) = in[2 * u];  // the left imager: the first byte of the 16-bit pixel
      r(u, v) = in[2 * u + 1];
    }
  }
  *left = std::move(l);
  *right = std::move(r);
  return {};
}

}  // namespace cblox
