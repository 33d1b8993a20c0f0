#pragma once

// cv::Mat views of cblox images, for code that hands them to OpenCV. Header-only: include it
// only where OpenCV's headers are available (core/geometry itself does not use OpenCV).

#include <cstdint>

#include <opencv2/core.hpp>

#include "core/geometry/image.h"

namespace cblox {

/// A CV_8UC1 cv::Mat sharing `image`'s pixels (no copy), for reading: OpenCV must not write
/// through it. Valid while `image` lives and is not resized. Thread-safe as reading `image`.
inline cv::Mat cvView(const GrayImage& image) {
  return cv::Mat(image.height, image.width, CV_8UC1, const_cast<uint8_t*>(image.data.data()));
}

/// A CV_8UC1 cv::Mat sharing `*image`'s pixels (no copy), for OpenCV to write into: give it
/// as an output of the same size and type and OpenCV writes in place (check `.data` after
/// the call if a reallocation would be a bug).
inline cv::Mat cvView(GrayImage* image) {
  return cv::Mat(image->height, image->width, CV_8UC1, image->data.data());
}

}  // namespace cblox
