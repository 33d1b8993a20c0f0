#include "drivers/sim/sim_source.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <vector>

namespace cblox {
namespace {

const SimSourceConfig& checked(const SimSourceConfig& config) {
  if (const std::string problem = config.validate(); !problem.empty()) {
    throw std::invalid_argument("SimSourceConfig: " + problem);
  }
  return config;
}

}  // namespace

std::string SimSourceConfig::validate() const {
  if (std::string problem = renderer.validate(); !problem.empty()) return problem;
  if (std::string problem = noise.validate(); !problem.empty()) return "noise: " + problem;
  if (!(rate_hz > 0.0) || !std::isfinite(rate_hz)) {
    return "rate_hz must be > 0, got " + std::to_string(rate_hz);
  }
  return {};
}

SimSource::SimSource(std::string name, std::shared_ptr<const TriangleMeshRaycaster> scene,
                     StampedTrajectory trajectory_G_L, const SimSourceConfig& config)
    : trajectory_(std::move(trajectory_G_L)),
      config_(checked(config)),
      renderer_(std::move(scene), config_.renderer),
      sensor_(config_.noise) {
  if (trajectory_.empty()) throw std::invalid_argument("SimSource: empty trajectory");
  const double span = trajectory_.back().timestamp_s - trajectory_.front().timestamp_s;
  frame_count_ = static_cast<size_t>(std::floor(span * config_.rate_hz + 1e-6)) + 1;
  if (config_.max_frames > 0) frame_count_ = std::min(frame_count_, config_.max_frames);

  const SimRigConfig& rig = config_.renderer.rig;
  info_.name = std::move(name);
  info_.rate_hz = config_.rate_hz;
  info_.stereo = rig.stereoCalibration();
  info_.depth_intrinsics = rig.depthIntrinsics();
  info_.T_C_D = rig.T_L_D;
  info_.depth_min_m = rig.depth_min_m;
  info_.depth_max_m = rig.depth_max_m;
  info_.frame_count = frame_count_;
  info_.has_ground_truth = true;
  if (config_.noise.any()) info_.notes.push_back("sensor noise on");
}

Transformationd SimSource::poseAt(double t) const {
  t = std::clamp(t, trajectory_.front().timestamp_s, trajectory_.back().timestamp_s);
  return *interpolatePose(trajectory_, t, std::numeric_limits<double>::infinity());
}

FrameSource::Status SimSource::next(CaptureFrame* frame, std::string* /*error*/) {
  while (next_ < frame_count_ && sensor_.dropFrame(static_cast<int64_t>(next_))) ++next_;
  if (next_ >= frame_count_) return Status::kEnd;
  const int64_t id = static_cast<int64_t>(next_++);
  const double t = trajectory_.front().timestamp_s + static_cast<double>(id) / config_.rate_hz;
  const Transformationd T_G_L = poseAt(t);

  const SensorNoiseConfig& noise = config_.noise;
  if (noise.exposure_time_s > 0.0 && noise.blur_samples > 1) {
    // Motion blur: depth and colour at the frame's pose (the same views render() makes);
    // the grey images are averages of renders spread over the exposure window.
    const SimRigConfig& rig = config_.renderer.rig;
    renderer_.renderView(rig.depthIsLeftCamera() ? T_G_L : T_G_L * rig.T_L_D,
                         rig.depthIntrinsics(), nullptr, &scratch_.color, &scratch_.depth);
    const Transformationd T_L_R(Eigen::Quaterniond::Identity(),
                                Eigen::Vector3d(rig.baseline_m, 0.0, 0.0));
    const size_t pixels = static_cast<size_t>(rig.stereo.width) * rig.stereo.height;
    std::vector<uint32_t> sum_left(pixels, 0), sum_right(pixels, 0);
    GrayImage left, right;
    for (int s = 0; s < noise.blur_samples; ++s) {
      const double ts = t + noise.exposure_time_s * ((s + 0.5) / noise.blur_samples - 0.5);
      const Transformationd T = poseAt(ts);
      renderer_.renderView(T, rig.stereo, &left, nullptr, nullptr);
      renderer_.renderView(T * T_L_R, rig.rightIntrinsics(), &right, nullptr, nullptr);
      for (size_t i = 0; i < pixels; ++i) sum_left[i] += left.data[i];
      for (size_t i = 0; i < pixels; ++i) sum_right[i] += right.data[i];
    }
    const uint32_t n = static_cast<uint32_t>(noise.blur_samples);
    for (size_t i = 0; i < pixels; ++i) {
      left.data[i] = static_cast<uint8_t>((sum_left[i] + n / 2) / n);
      right.data[i] = static_cast<uint8_t>((sum_right[i] + n / 2) / n);
    }
    std::swap(scratch_.left, left);
    std::swap(scratch_.right, right);
  } else {
    renderer_.render(T_G_L, &scratch_);
  }
  const double gain = sensor_.gain(t - trajectory_.front().timestamp_s);
  sensor_.applyImageNoise(id, 0, gain, &scratch_.left);
  sensor_.applyImageNoise(id, 1, gain, &scratch_.right);
  sensor_.applyDepthNoise(id, &scratch_.depth);

  frame->frame_id = id;
  frame->timestamp_ns = std::llround(t * 1e9);
  std::swap(frame->left, scratch_.left);
  std::swap(frame->right, scratch_.right);
  std::swap(frame->depth, scratch_.depth);
  std::swap(frame->color, scratch_.color);
  frame->T_G_C = T_G_L;
  return Status::kFrame;
}

}  // namespace cblox
