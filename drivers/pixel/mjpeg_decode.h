#pragma once

// MJPEG (one JPEG per frame) decoding with libjpeg-turbo. Internal to cblox_pixel.

#include <cstdint>
#include <vector>

#include "drivers/pixel/raw_image.h"

namespace cblox {

/// Output pixel layout of decodeMjpeg().
enum class JpegOutput { kGray, kRgb };

/// Decodes the JPEG stream raw.data[0, raw.bytes) (raw.format kMjpeg, already checked by
/// checkRawImage) into *pixels (non-null): width * height bytes for kGray, 3 * width * height
/// (R G B) for kRgb, rows packed. Streams without Huffman tables (UVC MJPEG) decode with the
/// standard tables of JPEG Annex K.3. Returns kDecodeFailed with libjpeg-turbo's message when
/// the header or data are corrupt or truncated (warnings included), or when the stream's size
/// is not raw.width x raw.height. *pixels is unspecified on failure. Thread-safe (one
/// libjpeg-turbo handle per call).
ConvertResult decodeMjpeg(const RawImage& raw, JpegOutput output, std::vector<uint8_t>* pixels);

}  // namespace cblox
