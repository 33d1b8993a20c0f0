#pragma once

// Conversions from camera pixel formats (pixel_format.h) to the images of core/geometry:
// grey for stereo, colour and depth for RGB-D, and the split of side-by-side and interleaved
// stereo frames.
// Every conversion checks the frame's size, stride and byte count (checkRawImage) before it
// reads a pixel, and leaves its output untouched when it fails.

#include "core/geometry/image.h"
#include "drivers/pixel/pixel_format.h"
#include "drivers/pixel/raw_image.h"

namespace cblox {

/// Converts `raw` to 8-bit grey in *out (non-null):
///   kGrey copied; kY16 its high byte (value >> 8); kYuyv, kUyvy, kNv12, kYuv420 the Y
///   samples as they are (limited range, not expanded); kRgb24, kBgr24, kXrgb8888 the BT.601
///   luma (77 R + 150 G + 29 B + 128) >> 8; kMjpeg decoded to grey by libjpeg-turbo.
/// Errors: checkRawImage()'s; kDecodeFailed for a JPEG stream that is corrupt, truncated
/// (warnings count as failures) or of another size than raw.width x raw.height, with
/// libjpeg-turbo's message; kUnsupported for kZ16, and for kY8i (two views in one frame:
/// splitInterleaved(), V4L2 mode side_by_side). Thread-safe (no shared state).
ConvertResult toGray(const RawImage& raw, GrayImage* out);

/// Converts `raw` to RGB in *out (non-null): the YUV formats by the BT.601 limited-range
/// equations (R = (298 (Y-16) + 409 (V-128) + 128) >> 8, G = (298 (Y-16) - 100 (U-128)
/// - 208 (V-128) + 128) >> 8, B = (298 (Y-16) + 516 (U-128) + 128) >> 8, clamped to
/// [0, 255]; each chroma sample shared by its 2 (4:2:2) or 2x2 (4:2:0) pixels); the RGB
/// formats reordered; kGrey and kY16 (high byte) as equal R, G, B; kMjpeg decoded.
/// Errors as toGray(); kUnsupported for kZ16 and kY8i. Thread-safe (no shared state).
ConvertResult toColor(const RawImage& raw, ColorImage* out);

/// Converts 16-bit depth units (kZ16, or kY16 from cameras that label depth so) to metres in
/// *out (non-null): value * metres_per_unit, computed in double and rounded to float; 0 (no
/// measurement) stays 0. Errors: checkRawImage()'s; kUnsupported for any other format or a
/// metres_per_unit that is not finite and > 0. Thread-safe (no shared state).
ConvertResult toDepth(const RawImage& raw, double metres_per_unit, DepthImage* out);

/// Splits a side-by-side stereo frame `both` (width 2W) into *left (columns [0, W)) and
/// *right (columns [W, 2W)), both non-null and distinct from `both`. Errors: kBadSize when
/// the width is odd or the image is empty; kShortBuffer when both.data holds fewer than
/// width * height pixels. Thread-safe (no shared state).
ConvertResult splitSideBySide(const GrayImage& both, GrayImage* left, GrayImage* right);

/// Splits an interleaved stereo frame `raw` (kY8i, width W) into *left (the first byte of each
/// 16-bit pixel) and *right (the second), each W x raw.height: the views are not halves of
/// the frame but each as wide as it. left and right non-null and distinct. Errors:
/// kUnsupported for any other format; checkRawImage()'s (size, stride, bytes). Leaves both
/// outputs untouched when it fails. Thread-safe (no shared state).
ConvertResult splitInterleaved(const RawImage& raw, GrayImage* left, GrayImage* right);

}  // namespace cblox
