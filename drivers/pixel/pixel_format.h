#pragma once

// Camera pixel formats shared by the camera drivers (V4L2, libcamera): names, fourcc codes
// and the memory layout of one frame.

#include <cstddef>
#include <cstdint>
#include <optional>
#include <string>
#include <string_view>

namespace cblox {

/// Pixel formats the camera drivers can convert. The memory layout of each (byte order as it
/// lies in memory, rows top to bottom, `stride` bytes apart):
///   kGrey      Y                  8-bit luma (V4L2 GREY)
///   kY16       Y0 Y1              16-bit little-endian luma (V4L2 "Y16 ")
///   kYuyv      Y0 U Y1 V          4:2:2 packed, 2 pixels per 4 bytes (V4L2 YUYV)
///   kUyvy      U Y0 V Y1          4:2:2 packed (V4L2 UYVY)
///   kNv12      Y plane, then one interleaved U V plane at half height, same stride (V4L2 NV12)
///   kYuv420    Y plane, U plane, V plane; chroma planes half width and height, stride/2
///              (V4L2 YU12 / I420)
///   kRgb24     R G B              (V4L2 RGB3; libcamera/DRM calls this BGR888!)
///   kBgr24     B G R              (V4L2 BGR3; libcamera/DRM calls this RGB888!)
///   kXrgb8888  B G R X            little-endian 32-bit xRGB words (DRM/libcamera XRGB8888,
///                                 V4L2 XR24 = V4L2_PIX_FMT_XBGR32, also the deprecated BGR4)
///   kMjpeg     one JPEG image per frame, possibly without Huffman tables (V4L2 MJPG / JPEG)
///   kZ16       16-bit little-endian depth units (V4L2 "Z16 ", e.g. Intel RealSense)
///   kY8i       L R                interleaved stereo grey (V4L2 "Y8I ", Intel RealSense IR
///                                 pair): 16 bits a pixel, the left imager's 8-bit value
///                                 first, the right's second; a W x H frame carries two
///                                 W x H views (splitInterleaved)
/// YUV formats are BT.601 limited range ("video range"); planes are contiguous.
enum class PixelFormat {
  kGrey,
  kY16,
  kYuyv,
  kUyvy,
  kNv12,
  kYuv420,
  kRgb24,
  kBgr24,
  kXrgb8888,
  kMjpeg,
  kZ16,
  kY8i
};

/// Short upper-case name: "GREY", "Y16", "YUYV", "UYVY", "NV12", "YUV420", "RGB24", "BGR24",
/// "XRGB8888", "MJPEG", "Z16", "Y8I". Thread-safe (pure).
std::string_view pixelFormatName(PixelFormat format);

/// Parses a name as pixelFormatName() writes it, case-insensitively; also accepts the V4L2
/// fourcc spellings "Y16 ", "YU12", "I420", "RGB3", "BGR3", "XR24", "MJPG", "JPEG", "Z16 ",
/// "Y8I ".
/// Returns std::nullopt for anything else. Thread-safe (pure).
std::optional<PixelFormat> pixelFormatFromName(std::string_view name);

/// Maps a V4L2 fourcc (V4L2_PIX_FMT_*) to its format; std::nullopt when not convertible here.
/// Accepts the aliases V4L2_PIX_FMT_JPEG (-> kMjpeg) and V4L2_PIX_FMT_BGR32 (-> kXrgb8888).
/// Thread-safe (pure).
std::optional<PixelFormat> pixelFormatFromFourcc(uint32_t fourcc);

/// Maps a DRM fourcc (as libcamera::PixelFormat::fourcc() returns) to its format, minding that
/// DRM names packed RGB by little-endian word order: DRM RGB888 ("RG24") is kBgr24 in memory,
/// DRM BGR888 ("BG24") is kRgb24. Also R8 -> kGrey, R16 -> kY16, YUYV, UYVY, NV12,
/// YU12 -> kYuv420, XR24 -> kXrgb8888, MJPG -> kMjpeg. std::nullopt for anything else (DRM
/// has no depth or interleaved-stereo format: never kZ16 or kY8i). Thread-safe (pure).
std::optional<PixelFormat> pixelFormatFromDrmFourcc(uint32_t fourcc);

/// The canonical V4L2 fourcc of `format` (e.g. V4L2_PIX_FMT_YUYV). Thread-safe (pure).
uint32_t fourccOf(PixelFormat format);

/// The four characters of a fourcc, lowest byte first, e.g. "YUYV", "Y16 "; non-printable
/// bytes become '.'. Thread-safe (pure).
std::string fourccToString(uint32_t fourcc);

/// Bytes of one row of the first plane without padding (e.g. 2 * width for YUYV and Y8I); 0 for
/// kMjpeg (compressed) and for width <= 0. Thread-safe (pure).
size_t minRowBytes(PixelFormat format, int width);

}  // namespace cblox
