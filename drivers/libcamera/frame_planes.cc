#include "drivers/libcamera/frame_planes.h"

#include <algorithm>

namespace cblox {
namespace {

// Bytes the camera wrote into a plane (its whole length when it did not say).
size_t usedBytes(const FramePlane& plane) {
  return plane.bytes_used == 0 ? plane.mapped.size()
                               : std::min(plane.bytes_used, plane.mapped.size());
}

// The planes of the format and the bytes each takes in the contiguous layout (the last
// plane's padding after its last row included: the converters need only requiredBytes()).
std::vector<size_t> planeSizes(PixelFormat format, int height, size_t stride) {
  const size_t rows = static_cast<size_t>(std::max(height, 0));
  switch (format) {
    case PixelFormat::kNv12:
      return {stride * rows, stride * (rows / 2)};
    case PixelFormat::kYuv420:
      return {stride * rows, (stride / 2) * (rows / 2), (stride / 2) * (rows / 2)};
    default:
      return {stride * rows};
  }
}

}  // namespace

RawImage assembleRawImage(PixelFormat format, int width, int height, size_t stride,
                          std::span<const FramePlane> planes, std::vector<uint8_t>* scratch) {
  RawImage raw;
  raw.format = format;
  raw.width = width;
  raw.height = height;
  raw.stride = stride;
  if (planes.empty()) return raw;
  raw.data = planes[0].mapped.data();
  if (format == PixelFormat::kMjpeg || planes.size() == 1) {
    raw.bytes = usedBytes(planes[0]);
    return raw;
  }
  const std::vector<size_t> sizes = planeSizes(format, height, effectiveStride(raw));
  const size_t count = std::min(sizes.size(), planes.size());
  if (count == 1) {
    raw.bytes = usedBytes(planes[0]);
    return raw;
  }
  // Back to back in one mapping: plane k starts where the layout puts it.
  bool contiguous = true;
  size_t offset = 0;
  for (size_t k = 0; k < count && contiguous; ++k) {
    contiguous = planes[k].mapped.data() == raw.data + offset;
    if (k + 1 < count) contiguous = contiguous && usedBytes(planes[k]) >= sizes[k];
    offset += sizes[k];
  }
  if (contiguous) {
    raw.bytes = offset - sizes[count - 1] + usedBytes(planes[count - 1]);
    return raw;
  }
  // Gather: each plane's share (or what it holds, if less) one after the other.
  scratch->clear();
  for (size_t k = 0; k < count; ++k) {
    const size_t take = std::min(sizes[k], usedBytes(planes[k]));
    scratch->insert(scratch->end(), planes[k].mapped.data(), planes[k].mapped.data() + take);
    if (take < sizes[k]) break;  // short plane: the converters report the shortfall
  }
  raw.data = scratch->data();
  raw.bytes = scratch->size();
  return raw;
}

}  // namespace cblox
