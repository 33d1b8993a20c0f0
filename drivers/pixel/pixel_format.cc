#include "drivers/pixel/pixel_format.h"

#include <linux/videodev2.h>

#include <array>
#include <cctype>

namespace cblox {
namespace {

constexpr uint32_t fourcc(char a, char b, char c, char d) {
  return static_cast<uint32_t>(static_cast<unsigned char>(a)) |
         (static_cast<uint32_t>(static_cast<unsigned char>(b)) << 8) |
         (static_cast<uint32_t>(static_cast<unsigned char>(c)) << 16) |
         (static_cast<uint32_t>(static_cast<unsigned char>(d)) << 24);
}

struct FormatEntry {
  PixelFormat format;
  std::string_view name;
  uint32_t v4l2;
};

constexpr std::array<FormatEntry, 12> kFormats = {{
    {PixelFormat::kGrey, "GREY", V4L2_PIX_FMT_GREY},
    {PixelFormat::kY16, "Y16", V4L2_PIX_FMT_Y16},
    {PixelFormat::kYuyv, "YUYV", V4L2_PIX_FMT_YUYV},
    {PixelFormat::kUyvy, "UYVY", V4L2_PIX_FMT_UYVY},
    {PixelFormat::kNv12, "NV12", V4L2_PIX_FMT_NV12},
    {PixelFormat::kYuv420, "YUV420", V4L2_PIX_FMT_YUV420},
    {PixelFormat::kRgb24, "RGB24", V4L2_PIX_FMT_RGB24},
    {PixelFormat::kBgr24, "BGR24", V4L2_PIX_FMT_BGR24},
    {PixelFormat::kXrgb8888, "XRGB8888", V4L2_PIX_FMT_XBGR32},
    {PixelFormat::kMjpeg, "MJPEG", V4L2_PIX_FMT_MJPEG},
    {PixelFormat::kZ16, "Z16", V4L2_PIX_FMT_Z16},
    {PixelFormat::kY8i, "Y8I", V4L2_PIX_FMT_Y8I},
}};

bool equalsIgnoreCase(std::string_view a, std::string_view b) {
  if (a.size() != b.size()) return false;
  for (size_t i = 0; i < a.size(); ++i) {
    if (std::toupper(static_cast<unsigned char>(a[i])) !=
        std::toupper(static_cast<unsigned char>(b[i]))) {
      return false;
    }
  }
  return true;
}

}  // namespace

std::string_view pixelFormatName(PixelFormat format) {
  for (const FormatEntry& entry : kFormats) {
    if (entry.format == format) return entry.name;
  }
  return "UNKNOWN";
}

std::optional<PixelFormat> pixelFormatFromName(std::string_view name) {
  for (const FormatEntry& entry : kFormats) {
    if (equalsIgnoreCase(name, entry.name) || equalsIgnoreCase(name, fourccToString(entry.v4l2))) {
      return entry.format;
    }
  }
  if (equalsIgnoreCase(name, "I420")) return PixelFormat::kYuv420;
  if (equalsIgnoreCase(name, "JPEG")) return PixelFormat::kMjpeg;
  return std::nullopt;
}

std::optional<PixelFormat> pixelFormatFromFourcc(uint32_t code) {
  for (const FormatEntry& entry : kFormats) {
    if (entry.v4l2 == code) return entry.format;
  }
  if (code == V4L2_PIX_FMT_JPEG) return PixelFormat::kMjpeg;
  if (code == V4L2_PIX_FMT_BGR32) return PixelFormat::kXrgb8888;
  return std::nullopt;
}

std::optional<PixelFormat> pixelFormatFromDrmFourcc(uint32_t code) {
  switch (code) {
    case fourcc('R', '8', ' ', ' '):
      return PixelFormat::kGrey;
    case fourcc('R', '1', '6', ' '):
      return PixelFormat::kY16;
    case fourcc('Y', 'U', 'Y', 'V'):
      return PixelFormat::kYuyv;
    case fourcc('U', 'Y', 'V', 'Y'):
      return PixelFormat::kUyvy;
    case fourcc('N', 'V', '1', '2'):
      return PixelFormat::kNv12;
    case fourcc('Y', 'U', '1', '2'):
      return PixelFormat::kYuv420;
    case fourcc('R', 'G', '2', '4'):
      return PixelFormat::kBgr24;  // DRM RGB888: B G R in memory
    case fourcc('B', 'G', '2', '4'):
      return PixelFormat::kRgb24;  // DRM BGR888: R G B in memory
    case fourcc('X', 'R', '2', '4'):
      return PixelFormat::kXrgb8888;
    case fourcc('M', 'J', 'P', 'G'):
      return PixelFormat::kMjpeg;
    default:
      return std::nullopt;
  }
}

uint32_t fourccOf(PixelFormat format) {
  for (const FormatEntry& entry : kFormats) {
    if (entry.format == format) return entry.v4l2;
  }
  return 0;
}

std::string fourccToString(uint32_t code) {
  std::string text(4, '.');
  for (int i = 0; i < 4; ++i) {
    const auto c = static_cast<unsigned char>((code >> (8 * i)) & 0xffu);
    if (std::isprint(c)) text[static_cast<size_t>(i)] = static_cast<char>(c);
  }
  return text;
}

size_t minRowBytes(PixelFormat format, int width) {
  if (width <= 0) return 0;
  const auto w = static_cast<size_t>(width);
  switch (format) {
    case PixelFormat::kGrey:
    case PixelFormat::kNv12:
    case PixelFormat::kYuv420:
      return w;
    case PixelFormat::kY16:
    case PixelFormat::kZ16:
    case PixelFormat::kYuyv:
    case PixelFormat::kUyvy:
    case PixelFormat::kY8i:
      return 2 * w;
    case PixelFormat::kRgb24:
    case PixelFormat::kBgr24:
      return 3 * w;
    case PixelFormat::kXrgb8888:
      return 4 * w;
    case PixelFormat::kMjpeg:
      return 0;
  }
  return 0;
}

}  // namespace cblox
