#include "drivers/synthetic/synthetic_frame_source.h"

#include <cmath>
#include <stdexcept>
#include <string>
#include <utility>

namespace cblox {

SyntheticDepthSource::SyntheticDepthSource(AnalyticScene scene, PinholeIntrinsics intrinsics,
                                           std::vector<Transformationd> trajectory, double rate_hz,
                                           double max_range)
    : scene_(std::move(scene)),
      camera_(intrinsics),
      trajectory_(std::move(trajectory)),
      rate_hz_(rate_hz),
      max_range_(max_range) {
  if (!(rate_hz > 0.0) || !std::isfinite(rate_hz)) {
    throw std::invalid_argument("SyntheticDepthSource: rate_hz must be > 0, got " +
                                std::to_string(rate_hz));
  }
  if (!(max_range > 0.0) || !std::isfinite(max_range)) {
    throw std::invalid_argument("SyntheticDepthSource: max_range must be > 0, got " +
                                std::to_string(max_range));
  }
}

bool SyntheticDepthSource::next(SyntheticFrame* frame) {
  if (next_index_ >= trajectory_.size()) return false;
  const size_t i = next_index_++;
  frame->timestamp_ns = std::llround(static_cast<double>(i) * 1e9 / rate_hz_);
  frame->T_G_C = trajectory_[i];
  scene_.renderDepth(frame->T_G_C, camera_, &frame->depth, &frame->color, max_range_);
  return true;
}

}  // namespace cblox
