#include "core/tracking/disparity_correction.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <vector>

namespace cblox {
namespace {

double median(std::vector<double> values) {
  const size_t mid = values.size() / 2;
  std::nth_element(values.begin(), values.begin() + static_cast<std::ptrdiff_t>(mid),
                   values.end());
  const double upper = values[mid];
  if (values.size() % 2 == 1) return upper;
  return 0.5 * (upper + *std::max_element(values.begin(),
                                          values.begin() + static_cast<std::ptrdiff_t>(mid)));
}

}  // namespace

std::string DisparityCorrectionConfig::validate() const {
  if (every_keyframes < 1) {
    return "every_keyframes must be >= 1, got " + std::to_string(every_keyframes);
  }
  if (settled_every_keyframes < 1) {
    return "settled_every_keyframes must be >= 1, got " + std::to_string(settled_every_keyframes);
  }
  if (window < 1) return "window must be >= 1, got " + std::to_string(window);
  if (min_estimates < 1 || min_estimates > window) {
    return "min_estimates must be in [1, window], got " + std::to_string(min_estimates);
  }
  if (!(max_spread_px > 0.0) || !std::isfinite(max_spread_px)) {
    return "max_spread_px must be > 0, got " + std::to_string(max_spread_px);
  }
  if (!(settled_tolerance_px > 0.0) || !std::isfinite(settled_tolerance_px)) {
    return "settled_tolerance_px must be > 0, got " + std::to_string(settled_tolerance_px);
  }
  if (!(min_correction_px >= 0.0) || !std::isfinite(min_correction_px)) {
    return "min_correction_px must be >= 0, got " + std::to_string(min_correction_px);
  }
  if (!(max_abs_px > 0.0) || !std::isfinite(max_abs_px)) {
    return "max_abs_px must be > 0, got " + std::to_string(max_abs_px);
  }
  if (std::string e = solver.validate(); !e.empty()) return "solver: " + e;
  return {};
}

DisparityCorrection::DisparityCorrection(const DisparityCorrectionConfig& config)
    : config_(config) {
  if (std::string e = config.validate(); !e.empty()) {
    throw std::invalid_argument("disparity correction: " + e);
  }
}

void DisparityCorrection::addEstimate(double offset_px) {
  std::lock_guard<std::mutex> lock(mutex_);
  if (!config_.enabled) return;
  if (!(std::abs(offset_px) <= config_.max_abs_px)) {
    ++stats_.refused;
    return;
  }
  ++stats_.estimates;
  stats_.last_estimate_px = offset_px;
  recent_.push_back(offset_px);
  if (static_cast<int>(recent_.size()) > config_.window) recent_.pop_front();
  settled_ = false;
  if (static_cast<int>(recent_.size()) < config_.min_estimates) return;
  const std::vector<double> values(recent_.begin(), recent_.end());
  const double m = median(values);
  std::vector<double> deviations;
  deviations.reserve(values.size());
  for (const double v : values) deviations.push_back(std::abs(v - m));
  stats_.spread_px = 1.4826 * median(deviations);
  if (stats_.spread_px > config_.max_spread_px) return;
  settled_ = static_cast<int>(recent_.size()) == config_.window &&
             std::abs(offset_px - m) <= config_.settled_tolerance_px;
  stats_.correction_px = std::abs(m) < config_.min_correction_px ? 0.0 : m;
  ++stats_.updates;
  correction_px_.store(static_cast<float>(stats_.correction_px), std::memory_order_relaxed);
}

bool DisparityCorrection::settled() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return settled_;
}

int DisparityCorrection::estimateInterval() const {
  return settled() ? config_.settled_every_keyframes : config_.every_keyframes;
}

DisparityCorrectionStats DisparityCorrection::stats() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return stats_;
}

}  // namespace cblox
