#include "daemon/tracker/image_check.h"

#include <cmath>
#include <cstdio>
#include <cstdlib>

namespace cblox {
namespace {

std::string percent(double fraction) {
  char text[32];
  std::snprintf(text, sizeof(text), "%.1f%%", 100.0 * fraction);
  return text;
}

}  // namespace

std::string ImageCheckConfig::validate() const {
  if (dark_level < 0 || dark_level > 255) return "dark_level must be in [0, 255]";
  if (bright_level < 0 || bright_level > 255) return "bright_level must be in [0, 255]";
  if (dark_level >= bright_level) return "dark_level must be below bright_level";
  if (!(max_fraction > 0.0 && max_fraction <= 1.0)) return "max_fraction must be in (0, 1]";
  if (!(min_mean_gradient >= 0.0) || !std::isfinite(min_mean_gradient)) {
    return "min_mean_gradient must be finite and >= 0";
  }
  return {};
}

std::optional<ImageCheckResult> checkImage(const GrayImage& image, const ImageCheckConfig& config,
                                           const std::string& name) {
  if (!config.enabled) return std::nullopt;
  if (image.empty()) return ImageCheckResult{ImageDefect::kDark, name + " is empty"};
  constexpr int kStep = 2;
  size_t samples = 0, dark = 0, bright = 0, gradient_samples = 0;
  uint64_t gradient_sum = 0;
  for (int v = 0; v < image.height; v += kStep) {
    for (int u = 0; u < image.width; u += kStep) {
      const int value = image(u, v);
      ++samples;
      dark += value <= config.dark_level ? 1 : 0;
      bright += value >= config.bright_level ? 1 : 0;
      if (u + 1 < image.width && v + 1 < image.height) {
        gradient_sum += static_cast<uint64_t>(std::abs(image(u + 1, v) - value) +
                                              std::abs(image(u, v + 1) - value));
        gradient_samples += 2;
      }
    }
  }
  const double n = static_cast<double>(samples);
  if (static_cast<double>(dark) >= config.max_fraction * n) {
    return ImageCheckResult{ImageDefect::kDark,
                            name + " is dark: " + percent(dark / n) +
                                " of pixels <= " + std::to_string(config.dark_level)};
  }
  if (static_cast<double>(bright) >= config.max_fraction * n) {
    return ImageCheckResult{ImageDefect::kSaturated,
                            name + " is saturated: " + percent(bright / n) +
                                " of pixels >= " + std::to_string(config.bright_level)};
  }
  const double mean_gradient = gradient_samples > 0 ? static_cast<double>(gradient_sum) /
                                                          static_cast<double>(gradient_samples)
                                                    : 0.0;
  if (mean_gradient < config.min_mean_gradient) {
    char text[96];
    std::snprintf(text, sizeof(text), " is textureless: mean gradient %.2f < %.2f grey levels",
                  mean_gradient, config.min_mean_gradient);
    return ImageCheckResult{ImageDefect::kTextureless, name + text};
  }
  return std::nullopt;
}

}  // namespace cblox
