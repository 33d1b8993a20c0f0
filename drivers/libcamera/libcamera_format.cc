#include "drivers/libcamera/libcamera_format.h"

#include <array>
#include <utility>

#include <libcamera/formats.h>

namespace cblox {
namespace {

namespace formats = libcamera::formats;

// Every convertible libcamera format and its cblox layout.
constexpr std::array<std::pair<libcamera::PixelFormat, PixelFormat>, 9> kFormats = {{
    {formats::R8, PixelFormat::kGrey},
    {formats::YUYV, PixelFormat::kYuyv},
    {formats::UYVY, PixelFormat::kUyvy},
    {formats::NV12, PixelFormat::kNv12},
    {formats::YUV420, PixelFormat::kYuv420},
    {formats::RGB888, PixelFormat::kBgr24},  // DRM RG24: B G R in memory
    {formats::BGR888, PixelFormat::kRgb24},  // DRM BG24: R G B in memory
    {formats::XRGB8888, PixelFormat::kXrgb8888},
    {formats::MJPEG, PixelFormat::kMjpeg},
}};

std::string acceptedNames() {
  std::string names;
  for (const auto& [libcamera_format, format] : kFormats) {
    if (!names.empty()) names += ", ";
    names +=
        std::string(pixelFormatName(format)) + " (libcamera " + libcamera_format.toString() + ")";
  }
  return names;
}

}  // namespace

std::optional<PixelFormat> pixelFormatFromLibcamera(const libcamera::PixelFormat& format) {
  if (format.modifier() != 0) return std::nullopt;
  for (const auto& [libcamera_format, cblox_format] : kFormats) {
    if (libcamera_format.fourcc() == format.fourcc()) return cblox_format;
  }
  return std::nullopt;
}

std::optional<libcamera::PixelFormat> libcameraFormatOf(PixelFormat format) {
  for (const auto& [libcamera_format, cblox_format] : kFormats) {
    if (cblox_format == format) return libcamera_format;
  }
  return std::nullopt;
}

std::optional<libcamera::PixelFormat> parseLibcameraPixelFormat(std::string_view name,
                                                                std::string* error) {
  if (const std::optional<PixelFormat> cblox_format = pixelFormatFromName(name)) {
    if (std::optional<libcamera::PixelFormat> format = libcameraFormatOf(*cblox_format)) {
      return format;
    }
    if (error != nullptr) {
      *error = "pixel format '" + std::string(name) +
               "' has no libcamera stream format; use one of " + acceptedNames();
    }
    return std::nullopt;
  }
  const libcamera::PixelFormat format = libcamera::PixelFormat::fromString(std::string(name));
  if (format.isValid() && pixelFormatFromLibcamera(format).has_value()) return format;
  if (error != nullptr) {
    *error = "pixel format '" + std::string(name) +
             (format.isValid() ? "' (a libcamera format) cannot be converted"
                               : "' is not a known pixel format name") +
             "; use one of " + acceptedNames();
  }
  return std::nullopt;
}

std::string describeLibcameraFormat(const libcamera::PixelFormat& format) {
  const std::optional<PixelFormat> cblox_format = pixelFormatFromLibcamera(format);
  if (!cblox_format) return format.toString();
  return std::string(pixelFormatName(*cblox_format)) + " (libcamera " + format.toString() + ")";
}

}  // namespace cblox
