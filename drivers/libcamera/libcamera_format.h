#pragma once

// The pixel formats of libcamera streams that cblox can convert, mapped to the shared
// formats of drivers/pixel (whose converters do the work).

#include <optional>
#include <string>
#include <string_view>

#include <libcamera/pixel_format.h>

#include "drivers/pixel/pixel_format.h"

namespace cblox {

/// Maps a libcamera stream format to the cblox layout with the same bytes in memory:
///   formats::R8 -> kGrey, YUYV -> kYuyv, UYVY -> kUyvy, NV12 -> kNv12, YUV420 -> kYuv420,
///   RGB888 -> kBgr24 and BGR888 -> kRgb24 (libcamera uses DRM names, which give the
///   little-endian word order: RGB888 lies in memory as B G R), XRGB8888 -> kXrgb8888
///   (B G R X in memory), MJPEG -> kMjpeg.
/// Returns std::nullopt for every other format, and for any of these with a non-zero
/// modifier (tiled or compressed layouts). Thread-safe (pure).
std::optional<PixelFormat> pixelFormatFromLibcamera(const libcamera::PixelFormat& format);

/// The inverse of pixelFormatFromLibcamera(): the libcamera format whose memory layout is
/// `format`; std::nullopt for kY16, kZ16 and kY8i (libcamera 0.0.3 has no such stream
/// format: 16-bit grey, depth, interleaved stereo).
/// Thread-safe (pure).
std::optional<libcamera::PixelFormat> libcameraFormatOf(PixelFormat format);

/// Parses the pixel format of a libcamera configuration. Accepts, case-insensitively, the
/// cblox names of pixelFormatName() and their V4L2 spellings (pixelFormatFromName(): "GREY",
/// "YUYV", "UYVY", "NV12", "YUV420", "RGB24" = R G B in memory, "BGR24", "XRGB8888",
/// "MJPEG", ...), then libcamera's own names as libcamera::PixelFormat::fromString() reads
/// them ("R8", "RGB888" = B G R in memory, "BGR888", "YUV420", ...; case-sensitive).
/// Returns std::nullopt and a message listing the accepted names in *error (if non-null)
/// when the name is neither, or names a format that cannot be converted (e.g. "Y16", "Y8I",
/// or libcamera's "SRGGB10"). Thread-safe (pure).
std::optional<libcamera::PixelFormat> parseLibcameraPixelFormat(std::string_view name,
                                                                std::string* error);

/// "<cblox name> (libcamera <libcamera name>)", e.g. "BGR24 (libcamera RGB888)", or just
/// libcamera's name for a format without a cblox mapping; for messages. Thread-safe.
std::string describeLibcameraFormat(const libcamera::PixelFormat& format);

}  // namespace cblox
