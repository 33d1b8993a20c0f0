#pragma once

#include <cstddef>
#include <string>

#include "core/geometry/color.h"
#include "core/geometry/image.h"
#include "core/geometry/pinhole_camera.h"
#include "core/geometry/point_cloud.h"  // also declares transformPointCloud()
#include "core/geometry/se3.h"

namespace cblox {

/// Settings for depthToPointCloud().
struct DepthConversionConfig {
  /// Depths below this (metres) are dropped as out of range. Must be finite and > 0.
  float min_depth_m = 0.1f;
  /// Depths above this (metres) are dropped as out of range. Must be finite and > min_depth_m.
  float max_depth_m = 5.0f;
  /// Use pixels whose column and row are both multiples of stride (1 = every pixel). >= 1.
  int stride = 1;

  /// Empty string if valid, else a message naming the first bad field, e.g.
  /// "min_depth_m must be finite and > 0, got -1". Thread-safe (pure).
  std::string validate() const;
};

/// Per-call counters of depthToPointCloud(). Only sampled pixels (see stride) are counted, so
/// valid + non_finite + non_positive + out_of_range == number of sampled pixels.
struct DepthConversionStats {
  size_t valid = 0;         // became a point
  size_t non_finite = 0;    // NaN or +-inf
  size_t non_positive = 0;  // <= 0 (0 is the usual "no return" value)
  size_t out_of_range = 0;  // finite and > 0 but outside [min_depth_m, max_depth_m]
};

/// Back-projects a depth image (metres along z) into camera-frame points (metres).
///
/// Samples the pixels (u, v) with u % stride == 0 and v % stride == 0, in row-major order
/// (v outer, u inner), and emits a point for each depth d that is finite and within
/// [min_depth_m, max_depth_m]: p_C = ((u - cx) / fx * d, (v - cy) / fy * d, d), so point z == d
/// exactly. Output points keep that row-major order. Invalid pixels are skipped and counted
/// in *stats (if non-null; stats is reset first).
///
/// color may be null; when given, the cloud carries the colour of each kept pixel.
/// Throws std::invalid_argument if the config is invalid, the depth image size differs from
/// the camera's (width x height), or color's size differs from depth's.
/// Thread-safe (pure).
PointCloud depthToPointCloud(const DepthImage& depth, const PinholeCamera& camera,
                             const ColorImage* color, const DepthConversionConfig& config,
                             DepthConversionStats* stats = nullptr);

}  // namespace cblox
