#include "drivers/pixel/raw_image.h"

namespace cblox {
namespace {

std::string describe(const RawImage& raw) {
  return std::string(pixelFormatName(raw.format)) + " " + std::to_string(raw.width) + "x" +
         std::to_string(raw.height);
}

ConvertResult fail(ConvertError error, std::string message) {
  return ConvertResult{error, std::move(message)};
}

bool isPlanar420(PixelFormat format) {
  return format == PixelFormat::kNv12 || format == PixelFormat::kYuv420;
}

}  // namespace

std::string_view convertErrorName(ConvertError error) {
  switch (error) {
    case ConvertError::kNone:
      return "none";
    case ConvertError::kShortBuffer:
      return "short_buffer";
    case ConvertError::kBadSize:
      return "bad_size";
    case ConvertError::kBadStride:
      return "bad_stride";
    case ConvertError::kDecodeFailed:
      return "decode_failed";
    case ConvertError::kUnsupported:
      return "unsupported";
  }
  return "unknown";
}

size_t effectiveStride(const RawImage& raw) {
  return raw.stride != 0 ? raw.stride : minRowBytes(raw.format, raw.width);
}

size_t requiredBytes(const RawImage& raw) {
  if (raw.format == PixelFormat::kMjpeg || raw.width <= 0 || raw.height <= 0 ||
      raw.width > kMaxImageSide || raw.height > kMaxImageSide) {
    return 0;
  }
  const size_t stride = effectiveStride(raw);
  if (stride > kMaxStride) return 0;
  const size_t row = minRowBytes(raw.format, raw.width);
  const auto h = static_cast<size_t>(raw.height);
  if (!isPlanar420(raw.format)) return stride * (h - 1) + row;
  // 4:2:0: chroma rows are half as many; NV12's interleaved UV row is as wide as a Y row,
  // each of YUV420's U and V rows half as wide, at half the stride.
  const size_t chroma_rows = (h + 1) / 2;
  const size_t luma = stride * h;
  if (raw.format == PixelFormat::kNv12) return luma + stride * (chroma_rows - 1) + row;
  const size_t chroma_stride = stride / 2;
  const size_t chroma_row = (row + 1) / 2;
  return luma + chroma_stride * chroma_rows + chroma_stride * (chroma_rows - 1) + chroma_row;
}

ConvertResult checkRawImage(const RawImage& raw) {
  if (raw.width <= 0 || raw.height <= 0 || raw.width > kMaxImageSide ||
      raw.height > kMaxImageSide) {
    return fail(ConvertError::kBadSize, describe(raw) + ": size must be within 1.." +
                                            std::to_string(kMaxImageSide) + " per side");
  }
  if ((raw.format == PixelFormat::kYuyv || raw.format == PixelFormat::kUyvy) &&
      raw.width % 2 != 0) {
    return fail(ConvertError::kBadSize, describe(raw) + ": width must be even for 4:2:2");
  }
  if (isPlanar420(raw.format) && (raw.width % 2 != 0 || raw.height % 2 != 0)) {
    return fail(ConvertError::kBadSize,
                describe(raw) + ": width and height must be even for 4:2:0");
  }
  if (raw.format == PixelFormat::kMjpeg) {
    if (raw.data == nullptr || raw.bytes == 0) {
      return fail(ConvertError::kShortBuffer, describe(raw) + ": empty JPEG stream");
    }
    return {};
  }
  const size_t row = minRowBytes(raw.format, raw.width);
  if (raw.stride > kMaxStride) {
    return fail(ConvertError::kBadStride, describe(raw) + ": stride " + std::to_string(raw.stride) +
                                              " exceeds " + std::to_string(kMaxStride) + " bytes");
  }
  if (raw.stride != 0 && raw.stride < row) {
    return fail(ConvertError::kBadStride, describe(raw) + ": stride " + std::to_string(raw.stride) +
                                              " is less than a row of " + std::to_string(row) +
                                              " bytes");
  }
  const size_t needed = requiredBytes(raw);
  if (raw.data == nullptr || raw.bytes < needed) {
    return fail(ConvertError::kShortBuffer,
                describe(raw) + ": buffer holds " +
                    std::to_string(raw.data == nullptr ? 0 : raw.bytes) + " bytes, needs " +
                    std::to_string(needed));
  }
  return {};
}

}  // namespace cblox
