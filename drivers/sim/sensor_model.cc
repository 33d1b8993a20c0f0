#include "drivers/sim/sensor_model.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <vector>

namespace cblox {
namespace {

constexpr double kTwoPi = 6.28318530717958647692;

bool isProbability(double p) { return p >= 0.0 && p <= 1.0; }

}  // namespace

std::string SensorNoiseConfig::validate() const {
  if (!(image_noise_sigma >= 0.0) || !std::isfinite(image_noise_sigma)) {
    return "image_noise_sigma must be >= 0, got " + std::to_string(image_noise_sigma);
  }
  if (!(exposure_amplitude >= 0.0 && exposure_amplitude < 1.0)) {
    return "exposure_amplitude must be in [0, 1), got " + std::to_string(exposure_amplitude);
  }
  if (!(exposure_period_s > 0.0) || !std::isfinite(exposure_period_s)) {
    return "exposure_period_s must be > 0, got " + std::to_string(exposure_period_s);
  }
  if (!(exposure_time_s >= 0.0 && exposure_time_s < 1.0)) {
    return "exposure_time_s must be in [0, 1) seconds, got " + std::to_string(exposure_time_s);
  }
  if (blur_samples < 1 || blur_samples > 32) {
    return "blur_samples must be in [1, 32], got " + std::to_string(blur_samples);
  }
  if (!(depth_noise_per_m2 >= 0.0) || !std::isfinite(depth_noise_per_m2)) {
    return "depth_noise_per_m2 must be >= 0, got " + std::to_string(depth_noise_per_m2);
  }
  if (!isProbability(depth_hole_probability)) return "depth_hole_probability must be in [0, 1]";
  if (!isProbability(depth_edge_hole_probability)) {
    return "depth_edge_hole_probability must be in [0, 1]";
  }
  if (!(frame_drop_probability >= 0.0 && frame_drop_probability < 1.0)) {
    return "frame_drop_probability must be in [0, 1)";
  }
  return {};
}

bool SensorNoiseConfig::any() const {
  return image_noise_sigma > 0.0 || exposure_amplitude > 0.0 || exposure_time_s > 0.0 ||
         depth_noise_per_m2 > 0.0 || depth_hole_probability > 0.0 ||
         depth_edge_hole_probability > 0.0 || frame_drop_probability > 0.0;
}

SensorModel::SensorModel(const SensorNoiseConfig& config) : config_(config) {
  if (const std::string problem = config.validate(); !problem.empty()) {
    throw std::invalid_argument("SensorNoiseConfig: " + problem);
  }
}

std::mt19937_64 SensorModel::rngFor(int64_t frame_id, int stream) const {
  std::seed_seq seq{config_.seed, static_cast<uint32_t>(frame_id),
                    static_cast<uint32_t>(static_cast<uint64_t>(frame_id) >> 32),
                    static_cast<uint32_t>(stream)};
  return std::mt19937_64(seq);
}

bool SensorModel::dropFrame(int64_t frame_id) const {
  if (config_.frame_drop_probability <= 0.0) return false;
  std::mt19937_64 rng = rngFor(frame_id, 100);
  return std::uniform_real_distribution<double>(0.0, 1.0)(rng) < config_.frame_drop_probability;
}

double SensorModel::gain(double t_s) const {
  return 1.0 + config_.exposure_amplitude * std::sin(kTwoPi * t_s / config_.exposure_period_s);
}

void SensorModel::applyImageNoise(int64_t frame_id, int stream, double gain,
                                  GrayImage* image) const {
  const bool scale = gain != 1.0;
  if (!scale && config_.image_noise_sigma <= 0.0) return;
  std::mt19937_64 rng = rngFor(frame_id, stream);
  std::normal_distribution<float> noise(0.0f, static_cast<float>(config_.image_noise_sigma));
  const float g = static_cast<float>(gain);
  const bool add_noise = config_.image_noise_sigma > 0.0;
  for (uint8_t& pixel : image->data) {
    float value = static_cast<float>(pixel) * g;
    if (add_noise) value += noise(rng);
    pixel = static_cast<uint8_t>(std::clamp(value + 0.5f, 0.0f, 255.0f));
  }
}

void SensorModel::applyDepthNoise(int64_t frame_id, DepthImage* depth) const {
  const double k = config_.depth_noise_per_m2;
  const double p_hole = config_.depth_hole_probability;
  const double p_edge = config_.depth_edge_hole_probability;
  if (k <= 0.0 && p_hole <= 0.0 && p_edge <= 0.0) return;
  std::mt19937_64 rng = rngFor(frame_id, 7);
  std::normal_distribution<float> unit_noise(0.0f, 1.0f);
  std::uniform_real_distribution<double> uniform(0.0, 1.0);
  const int w = depth->width, h = depth->height;
  // Edge holes are decided on the exact depth, before noise.
  std::vector<uint8_t> edge;
  if (p_edge > 0.0) {
    edge.assign(depth->data.size(), 0);
    auto jump = [](float a, float b) {
      if (a <= 0.0f || b <= 0.0f) return a > 0.0f || b > 0.0f;
      return std::abs(a - b) > 0.05f * std::min(a, b);
    };
    for (int v = 0; v < h; ++v) {
      for (int u = 0; u < w; ++u) {
        const float d = (*depth)(u, v);
        if (d <= 0.0f) continue;
        const bool at_edge = (u > 0 && jump(d, (*depth)(u - 1, v))) ||
                             (u + 1 < w && jump(d, (*depth)(u + 1, v))) ||
                             (v > 0 && jump(d, (*depth)(u, v - 1))) ||
                             (v + 1 < h && jump(d, (*depth)(u, v + 1)));
        edge[static_cast<size_t>(v) * w + u] = at_edge;
      }
    }
  }
  for (size_t i = 0; i < depth->data.size(); ++i) {
    float& d = depth->data[i];
    if (!(d > 0.0f)) continue;
    if ((p_hole > 0.0 && uniform(rng) < p_hole) ||
        (p_edge > 0.0 && edge[i] && uniform(rng) < p_edge)) {
      d = 0.0f;
      continue;
    }
    if (k > 0.0) {
      const float noisy = d + static_cast<float>(k) * d * d * unit_noise(rng);
      d = noisy > 0.0f ? noisy : 0.0f;
    }
  }
}

}  // namespace cblox
