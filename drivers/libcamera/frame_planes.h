#pragma once

// Turning the planes of a completed libcamera buffer into the one contiguous RawImage the
// converters of drivers/pixel read.

#include <cstddef>
#include <cstdint>
#include <span>
#include <vector>

#include "drivers/pixel/raw_image.h"

namespace cblox {

/// One plane of a completed buffer: its mapped bytes and how many the camera wrote.
struct FramePlane {
  std::span<const uint8_t> mapped;  ///< the whole plane (FrameBuffer::Plane::length)
  size_t bytes_used = 0;            ///< FrameMetadata::Plane::bytesused; 0 = unknown
};

/// Builds the RawImage of a frame of `format`, width x height, first-plane stride `stride`
/// (0 = packed), from its planes, in the layout pixel_format.h describes (planes contiguous:
/// NV12's UV plane right after the Y plane's height rows; YUV420's U then V planes at half
/// the stride). When the planes already lie so in memory (one plane, or planes of one
/// dmabuf back to back) the image points into them (no copy); otherwise the planes are
/// copied one after the other into *scratch (non-null) and the image points there.
/// The image's byte count is what the camera wrote (bytes_used, or the plane length when
/// 0), so a short frame is caught by the converters as kShortBuffer; for kMjpeg it is the
/// first plane's bytes_used (the JPEG stream's size). Planes beyond what the format has are
/// ignored; missing ones leave the image short. Never fails. Thread-safe (no shared state;
/// *scratch is the caller's).
RawImage assembleRawImage(PixelFormat format, int width, int height, size_t stride,
                          std::span<const FramePlane> planes, std::vector<uint8_t>* scratch);

}  // namespace cblox
