#include "drivers/stereo_depth/depth_accuracy.h"

#include <algorithm>
#include <cmath>
#include <map>
#include <stdexcept>
#include <string>

#include "core/common/quantile.h"

namespace cblox {

DepthAccuracy compareToExactDepth(const DepthImage& estimate, int downscale,
                                  const DepthImage& exact, double bin_width_m) {
  if (downscale < 1 || estimate.width != exact.width / downscale ||
      estimate.height != exact.height / downscale || !(bin_width_m > 0)) {
    throw std::invalid_argument("compareToExactDepth: estimate " + std::to_string(estimate.width) +
                                "x" + std::to_string(estimate.height) + " is not 1/" +
                                std::to_string(downscale) + " of " + std::to_string(exact.width) +
                                "x" + std::to_string(exact.height));
  }
  DepthAccuracy accuracy;
  std::vector<double> abs_errors, rel_errors;
  std::map<long, std::vector<double>> by_bin;
  size_t outliers = 0;
  for (int v = 0; v < estimate.height; ++v) {
    for (int u = 0; u < estimate.width; ++u) {
      double sum = 0.0, lo = INFINITY, hi = 0.0;
      bool usable = true;
      for (int dv = 0; dv < downscale && usable; ++dv) {
        for (int du = 0; du < downscale; ++du) {
          const float z = exact(u * downscale + du, v * downscale + dv);
          if (!(z > 0.0f) || !std::isfinite(z)) {
            usable = false;
            break;
          }
          sum += z;
          lo = std::min<double>(lo, z);
          hi = std::max<double>(hi, z);
        }
      }
      if (!usable || hi > 1.02 * lo) continue;
      ++accuracy.reference;
      const float e = estimate(u, v);
      if (!(e > 0.0f) || !std::isfinite(e)) continue;
      const double z = sum / (downscale * downscale);
      const double error = std::abs(e - z);
      abs_errors.push_back(error);
      rel_errors.push_back(error / z);
      outliers += error > 0.1 * z;
      by_bin[static_cast<long>(std::floor(z / bin_width_m))].push_back(error);
    }
  }
  accuracy.compared = abs_errors.size();
  if (accuracy.reference > 0) {
    accuracy.completeness = static_cast<double>(accuracy.compared) / accuracy.reference;
  }
  if (accuracy.compared > 0) {
    accuracy.outlier_fraction = static_cast<double>(outliers) / accuracy.compared;
  }
  accuracy.median_abs_m = quantile(&abs_errors, 0.5);
  accuracy.p90_abs_m = quantile(&abs_errors, 0.9);
  accuracy.median_rel = quantile(&rel_errors, 0.5);
  accuracy.p90_rel = quantile(&rel_errors, 0.9);
  for (auto& [bin, errors] : by_bin) {
    DepthErrorBin b;
    b.z_min_m = bin * bin_width_m;
    b.z_max_m = (bin + 1) * bin_width_m;
    b.samples = errors.size();
    b.median_abs_m = quantile(&errors, 0.5);
    b.p90_abs_m = quantile(&errors, 0.9);
    accuracy.bins.push_back(b);
  }
  return accuracy;
}

}  // namespace cblox
