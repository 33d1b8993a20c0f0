#pragma once

#include <optional>
#include <string>

#include "core/geometry/image.h"

namespace cblox {

/// Settings of the tracker's check for images that cannot be tracked at all (lens cap,
/// blinded or saturated sensor, a view of a blank wall). Deliberately coarse: only frames in
/// which the feature extractor could find nothing are caught; everything else goes to the
/// tracker, which reports LOST with its own reason when tracking fails. Plain value type.
struct ImageCheckConfig {
  bool enabled = true;
  /// Pixels at or below this grey level count as dark, at or above bright_level as
  /// saturated, [0, 255], dark_level < bright_level.
  int dark_level = 10;
  int bright_level = 245;
  /// An image is "dark" / "saturated" when at least this fraction of its pixels is, (0, 1].
  double max_fraction = 0.95;
  /// An image is "textureless" when its mean absolute grey-level difference between
  /// neighbouring pixels (horizontal and vertical, averaged) is below this, grey levels per
  /// pixel, >= 0. The simulator's textured scenes measure 8-20; a uniform image 0.
  double min_mean_gradient = 1.0;

  /// Empty when valid, otherwise a message naming the offending field. Thread-safe.
  std::string validate() const;
};

/// Why an image cannot be tracked.
enum class ImageDefect { kDark, kSaturated, kTextureless };

/// What the check found: the defect and a human-readable description with the measured
/// figures, e.g. "left image is dark: 99.8% of pixels <= 10".
struct ImageCheckResult {
  ImageDefect defect = ImageDefect::kDark;
  std::string description;
};

/// Checks one image (every second row and column are sampled; ~0.3 ms at 752x480). `name`
/// starts the description ("left image"). Returns std::nullopt for a usable image or when
/// the check is disabled; an empty image is "dark". Thread-safe (pure).
std::optional<ImageCheckResult> checkImage(const GrayImage& image, const ImageCheckConfig& config,
                                           const std::string& name);

}  // namespace cblox
