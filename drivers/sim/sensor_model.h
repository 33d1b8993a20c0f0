#pragma once

#include <cstdint>
#include <random>
#include <string>

#include "core/geometry/image.h"

namespace cblox {

/// Sensor realism added to the simulator's exact images. Every effect is off at its zero
/// value, so the default config delivers exact images. Plain value type.
struct SensorNoiseConfig {
  /// Gaussian noise on the grey images, standard deviation in grey levels.
  double image_noise_sigma = 0.0;
  /// Auto-exposure drift: both cameras' gain is 1 + amplitude * sin(2 pi t / period).
  double exposure_amplitude = 0.0;
  double exposure_period_s = 7.0;
  /// Motion blur: grey images average `blur_samples` renders spread over the exposure time
  /// (0 = off).
  double exposure_time_s = 0.0;
  int blur_samples = 4;
  /// Depth noise: sigma = depth_noise_per_m2 * z^2 metres (RealSense D435 is about 0.001-0.002).
  double depth_noise_per_m2 = 0.0;
  /// Probability that a depth pixel is missing, independently per pixel.
  double depth_hole_probability = 0.0;
  /// Probability that a depth pixel next to a depth discontinuity (> 5 % jump) is missing,
  /// like the invalid bands structured-light and stereo depth sensors leave at object edges.
  double depth_edge_hole_probability = 0.0;
  /// Probability that a whole frame is dropped (not delivered; its frame id is skipped).
  double frame_drop_probability = 0.0;
  /// Seed: the same seed gives the same noise for the same frame id.
  uint32_t seed = 1;

  /// Empty when valid, else a message naming the first bad field. Thread-safe.
  std::string validate() const;
  /// True when some effect is on.
  bool any() const;
};

/// Applies the sensor model. Every function is deterministic in (config.seed, frame_id) and
/// thread-safe (pure apart from its output argument).
class SensorModel {
 public:
  /// Throws std::invalid_argument with validate()'s message.
  explicit SensorModel(const SensorNoiseConfig& config);

  /// True if frame `frame_id` is dropped.
  bool dropFrame(int64_t frame_id) const;
  /// Exposure gain at time t (seconds).
  double gain(double t_s) const;
  /// Scales by `gain` and adds Gaussian noise; `stream` separates the two cameras' noise.
  void applyImageNoise(int64_t frame_id, int stream, double gain, GrayImage* image) const;
  /// Adds z^2 noise and holes (random and at depth edges); ranges are not touched.
  void applyDepthNoise(int64_t frame_id, DepthImage* depth) const;

  const SensorNoiseConfig& config() const { return config_; }

 private:
  std::mt19937_64 rngFor(int64_t frame_id, int stream) const;

  SensorNoiseConfig config_;
};

}  // namespace cblox
