#pragma once

#include <cstddef>
#include <vector>

#include "core/geometry/image.h"

namespace cblox {

/// Error of estimated depth against exact depth in one range of z. Plain value type.
struct DepthErrorBin {
  double z_min_m = 0.0, z_max_m = 0.0;
  size_t samples = 0;
  double median_abs_m = 0.0;
  double p90_abs_m = 0.0;
};

/// How an estimated depth image compares with the exact one. Plain value type.
struct DepthAccuracy {
  size_t compared = 0;         ///< estimated pixels with a usable exact depth
  size_t reference = 0;        ///< pixels with a usable exact depth
  double completeness = 0.0;   ///< compared / reference
  double median_abs_m = 0.0;   ///< median |z_est - z_exact|
  double p90_abs_m = 0.0;
  double median_rel = 0.0;     ///< median |z_est - z_exact| / z_exact
  double p90_rel = 0.0;
  double outlier_fraction = 0.0;  ///< share of compared pixels with relative error > 10 %
  std::vector<DepthErrorBin> bins;  ///< by exact z, bin_width_m wide, empty bins dropped
};

/// Compares `estimate` (depth at 1/downscale of the exact image's resolution, as
/// StereoDepthEstimator makes it) with `exact`: each estimate pixel (u, v) covers the
/// downscale x downscale block of exact pixels starting at (u * downscale, v * downscale); the
/// reference depth is the block's mean, and the pixel is left out of both counts where the
/// block has a missing depth or spans more than 2 % in z (a depth edge, where the true depth
/// of the pixel is ambiguous). Pixels <= 0 or non-finite in `estimate` are "no estimate".
/// Throws std::invalid_argument when the sizes do not correspond. Thread-safe (pure).
DepthAccuracy compareToExactDepth(const DepthImage& estimate, int downscale,
                                  const DepthImage& exact, double bin_width_m = 1.0);

}  // namespace cblox
