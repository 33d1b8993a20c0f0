#pragma once

#include <Eigen/Core>

#include "core/geometry/color.h"

namespace cblox {

/// Procedural checkerboard on a surface's 2D coordinates (metres): squares of side cell_size
/// alternate between colours a and b. cell_size <= 0 (or non-finite) gives plain colour a.
/// Plain value type; thread-safe to read concurrently.
struct CheckerTexture {
  Color a;
  Color b;
  double cell_size = 0.0;  // metres; <= 0 means a solid colour

  /// A texture of one plain colour. Thread-safe (pure).
  static CheckerTexture solid(const Color& c) { return CheckerTexture{c, c, 0.0}; }

  /// Colour at surface coordinates uv (metres): a where floor(u / s) + floor(v / s) is even,
  /// b where it is odd. Thread-safe (pure).
  Color colorAt(const Eigen::Vector2d& uv) const;
};

}  // namespace cblox
