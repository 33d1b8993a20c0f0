#pragma once

#include <cstddef>
#include <cstdint>
#include <stdexcept>
#include <string>
#include <vector>

#include "core/geometry/color.h"

namespace cblox {

/// Dense row-major image: pixel (u, v) (u = column, v = row) lives at data[v * width + u].
/// Plain value type: concurrent reads are thread-safe, writes need external synchronisation.
template <typename T>
struct Image {
  int width = 0;
  int height = 0;
  std::vector<T> data;

  Image() = default;

  /// Allocates w x h pixels set to `fill`. Throws std::invalid_argument if w or h is negative.
  Image(int w, int h, T fill = T{}) : width(w), height(h) {
    if (w < 0 || h < 0) {
      throw std::invalid_argument("Image size must be >= 0, got " + std::to_string(w) + "x" +
                                  std::to_string(h));
    }
    data.assign(static_cast<size_t>(w) * static_cast<size_t>(h), fill);
  }

  /// Unchecked access to pixel (u, v); the caller guarantees contains(u, v).
  T& operator()(int u, int v) { return data[index(u, v)]; }
  /// Unchecked access to pixel (u, v); the caller guarantees contains(u, v).
  const T& operator()(int u, int v) const { return data[index(u, v)]; }

  /// True if the image has no pixels.
  bool empty() const { return width <= 0 || height <= 0 || data.empty(); }

  /// True if (u, v) is inside [0, width) x [0, height).
  bool contains(int u, int v) const { return u >= 0 && u < width && v >= 0 && v < height; }

  /// True if `other` has the same width and height (pixel types may differ).
  template <typename U>
  bool sameSize(const Image<U>& other) const {
    return width == other.width && height == other.height;
  }

 private:
  size_t index(int u, int v) const {
    return static_cast<size_t>(v) * static_cast<size_t>(width) + static_cast<size_t>(u);
  }
};

/// Depth in metres along the camera z axis. 0, negative, NaN and inf mean "no measurement".
using DepthImage = Image<float>;
/// RGB colour image.
using ColorImage = Image<Color>;
/// 8-bit intensity image (e.g. one camera of a stereo pair).
using GrayImage = Image<uint8_t>;

}  // namespace cblox
