#include "drivers/sim/sensor_model.h"

#include <cmath>

#include <gtest/gtest.h>

namespace cblox {
namespace {

TEST(SensorModelTest, DefaultConfigChangesNothing) {
  const SensorModel model{SensorNoiseConfig{}};
  EXPECT_FALSE(model.config().any());
  DepthImage depth(8, 8, 2.0f);
  GrayImage gray(8, 8, 100);
  model.applyDepthNoise(3, &depth);
  model.applyImageNoise(3, 0, model.gain(1.0), &gray);
  for (float d : depth.data) EXPECT_EQ(d, 2.0f);
  for (uint8_t g : gray.data) EXPECT_EQ(g, 100);
  EXPECT_FALSE(model.dropFrame(0));
}

TEST(SensorModelTest, DepthNoiseGrowsWithDepthSquared) {
  SensorNoiseConfig config;
  config.depth_noise_per_m2 = 0.002;
  const SensorModel model(config);
  for (float z : {1.0f, 3.0f}) {
    DepthImage depth(200, 200, z);
    model.applyDepthNoise(1, &depth);
    double sum = 0, sum2 = 0;
    for (float d : depth.data) sum += d - z, sum2 += (d - z) * (d - z);
    const double n = static_cast<double>(depth.data.size());
    const double sigma = std::sqrt(sum2 / n - (sum / n) * (sum / n));
    EXPECT_NEAR(sigma, 0.002 * z * z, 0.03 * 0.002 * z * z) << z;
    EXPECT_NEAR(sum / n, 0.0, 4 * 0.002 * z * z / std::sqrt(n));
  }
}

TEST(SensorModelTest, HolesAppearAtTheConfiguredRateAndAtEdges) {
  SensorNoiseConfig config;
  config.depth_hole_probability = 0.1;
  DepthImage depth(100, 100, 2.0f);
  SensorModel(config).applyDepthNoise(5, &depth);
  const double holes = std::count(depth.data.begin(), depth.data.end(), 0.0f) / 10000.0;
  EXPECT_NEAR(holes, 0.1, 0.015);

  SensorNoiseConfig edges;
  edges.depth_edge_hole_probability = 1.0;
  DepthImage step(20, 10, 1.0f);
  for (int v = 0; v < 10; ++v) {
    for (int u = 10; u < 20; ++u) step(u, v) = 2.0f;
  }
  SensorModel(edges).applyDepthNoise(5, &step);
  for (int v = 0; v < 10; ++v) {
    for (int u = 0; u < 20; ++u) {
      const bool at_edge = u == 9 || u == 10;
      EXPECT_EQ(step(u, v) == 0.0f, at_edge) << u << ", " << v;
    }
  }
}

TEST(SensorModelTest, ImageNoiseGainAndFrameDropsAreDeterministic) {
  SensorNoiseConfig config;
  config.image_noise_sigma = 4.0;
  config.exposure_amplitude = 0.2;
  config.exposure_period_s = 4.0;
  config.frame_drop_probability = 0.2;
  const SensorModel model(config);
  EXPECT_NEAR(model.gain(1.0), 1.2, 1e-12);  // sin(pi / 2)
  EXPECT_NEAR(model.gain(3.0), 0.8, 1e-12);
  GrayImage a(64, 64, 100), b(64, 64, 100), c(64, 64, 100);
  model.applyImageNoise(9, 0, 1.0, &a);
  model.applyImageNoise(9, 0, 1.0, &b);
  model.applyImageNoise(9, 1, 1.0, &c);
  EXPECT_EQ(a.data, b.data);
  EXPECT_NE(a.data, c.data);  // the other camera's noise is independent
  double sum = 0, sum2 = 0;
  for (uint8_t g : a.data) sum += g - 100.0, sum2 += (g - 100.0) * (g - 100.0);
  EXPECT_NEAR(std::sqrt(sum2 / a.data.size()), 4.0, 0.25);
  GrayImage bright(4, 4, 100);
  SensorModel(SensorNoiseConfig{}).applyImageNoise(1, 0, 1.2, &bright);
  EXPECT_EQ(bright(0, 0), 120);
  int dropped = 0;
  for (int i = 0; i < 2000; ++i) {
    dropped += model.dropFrame(i);
    EXPECT_EQ(model.dropFrame(i), model.dropFrame(i));
  }
  EXPECT_NEAR(dropped / 2000.0, 0.2, 0.03);
}

TEST(SensorModelTest, RejectsInvalidConfig) {
  SensorNoiseConfig config;
  config.depth_hole_probability = 1.5;
  EXPECT_THROW(SensorModel{config}, std::invalid_argument);
  config = SensorNoiseConfig{};
  config.blur_samples = 0;
  EXPECT_NE(config.validate().find("blur_samples"), std::string::npos);
  config = SensorNoiseConfig{};
  config.frame_drop_probability = 1.0;
  EXPECT_FALSE(config.validate().empty());
}

}  // namespace
}  // namespace cblox
