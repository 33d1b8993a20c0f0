#pragma once

// A camera frame as the driver hands it over (a borrowed view of its bytes), and the result
// of checking or converting one.

#include <cstddef>
#include <cstdint>
#include <string>
#include <string_view>

#include "drivers/pixel/pixel_format.h"

namespace cblox {

/// A borrowed, read-only view of one frame in a camera pixel format (layouts in
/// pixel_format.h). Does not own `data`: valid only while the driver's buffer is.
/// Plain value type.
struct RawImage {
  PixelFormat format = PixelFormat::kGrey;
  int width = 0;
  int height = 0;
  /// Bytes per row of the first plane, padding included; 0 = packed (minRowBytes()).
  /// Ignored for kMjpeg.
  size_t stride = 0;
  const uint8_t* data = nullptr;
  /// Bytes readable at `data` (V4L2 bytesused): for kMjpeg the size of the JPEG stream.
  size_t bytes = 0;
};

/// Why a conversion failed.
enum class ConvertError {
  kNone,          ///< success
  kShortBuffer,   ///< fewer bytes than the layout needs (or no data)
  kBadSize,       ///< width/height out of (0, kMaxImageSide], odd where the format needs even
  kBadStride,     ///< stride smaller than one row of pixels
  kDecodeFailed,  ///< MJPEG stream corrupt, truncated, or of another size than announced
  kUnsupported,   ///< this conversion is not defined for the format (or a bad argument)
};

/// Largest width or height accepted by every conversion.
inline constexpr int kMaxImageSide = 16384;

/// Largest stride (bytes per row) accepted by every conversion.
inline constexpr size_t kMaxStride = size_t{1} << 20;

/// "none", "short_buffer", "bad_size", "bad_stride", "decode_failed", "unsupported";
/// usable as a counter key. Thread-safe (pure).
std::string_view convertErrorName(ConvertError error);

/// Outcome of a conversion: error kNone on success, else the kind and a message that names
/// the format and size, e.g. "YUYV 640x480: buffer holds 1000 bytes, needs 614400".
/// Plain value type.
struct ConvertResult {
  ConvertError error = ConvertError::kNone;
  std::string message;

  /// True on success.
  explicit operator bool() const { return error == ConvertError::kNone; }
};

/// Checks `raw` before anything reads its pixels: width and height in (0, kMaxImageSide];
/// even width for kYuyv/kUyvy and even width and height for kNv12/kYuv420 (kBadSize);
/// stride 0 or within [minRowBytes(), kMaxStride] (kBadStride); data non-null and bytes >=
/// requiredBytes() (kShortBuffer). For kMjpeg only the size and that bytes > 0. Thread-safe (pure).
ConvertResult checkRawImage(const RawImage& raw);

/// Bytes a frame of raw's format, size and stride occupies, the padding after the last row
/// of the last plane excepted; 0 for kMjpeg or an invalid size. Thread-safe (pure).
size_t requiredBytes(const RawImage& raw);

/// raw.stride, or minRowBytes() when it is 0. Thread-safe (pure).
size_t effectiveStride(const RawImage& raw);

}  // namespace cblox
