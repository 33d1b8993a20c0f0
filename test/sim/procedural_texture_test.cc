#include "drivers/sim/procedural_texture.h"

#include <algorithm>
#include <cmath>
#include <random>
#include <vector>

#include <gtest/gtest.h>

namespace cblox {
namespace {

std::vector<ProceduralTexture::TextureSample> randomSamples(int n, float footprint_max) {
  std::mt19937 rng(3);
  std::uniform_real_distribution<float> coord(-150.0f, 150.0f), unit(-1.0f, 1.0f),
      footprint(0.0f, footprint_max);
  std::vector<ProceduralTexture::TextureSample> samples;
  for (int i = 0; i < n; ++i) {
    samples.push_back({Eigen::Vector3f(coord(rng), coord(rng), coord(rng)),
                       Eigen::Vector3f(unit(rng), unit(rng), unit(rng)), footprint(rng)});
  }
  return samples;
}

TEST(ProceduralTextureTest, ValuesStayInTheContrastRangeAndUseIt) {
  ProceduralTextureConfig config;
  config.contrast = 0.6;
  const ProceduralTexture texture(config);
  const auto samples = randomSamples(5000, 0.02f);
  std::vector<float> values(samples.size());
  texture.brightness(samples, values);
  float lo = 2.0f, hi = -1.0f;
  for (float v : values) {
    ASSERT_GE(v, 0.4f - 1e-6f);
    ASSERT_LE(v, 1.0f + 1e-6f);
    lo = std::min(lo, v), hi = std::max(hi, v);
  }
  EXPECT_LT(lo, 0.5f);
  EXPECT_GT(hi, 0.9f);
}

TEST(ProceduralTextureTest, BatchEqualsSingleAndSeedsDiffer) {
  const ProceduralTexture texture{ProceduralTextureConfig{}};
  const auto samples = randomSamples(37, 0.01f);  // not a multiple of 8
  std::vector<float> batch(samples.size());
  texture.brightness(samples, batch);
  for (size_t i = 0; i < samples.size(); ++i) {
    EXPECT_EQ(batch[i], texture.brightness(samples[i].point, samples[i].normal,
                                           samples[i].footprint_m));
  }
  ProceduralTextureConfig other;
  other.seed = 2;
  std::vector<float> other_values(samples.size());
  ProceduralTexture(other).brightness(samples, other_values);
  EXPECT_NE(batch, other_values);
}

TEST(ProceduralTextureTest, Avx2AndPortablePathsAgree) {
  ProceduralTexture texture{ProceduralTextureConfig{}};
  if (!texture.usesAvx2()) GTEST_SKIP() << "this CPU has no AVX2/FMA";
  const auto samples = randomSamples(4096, 0.05f);
  std::vector<float> avx2(samples.size()), portable(samples.size());
  texture.brightness(samples, avx2);
  texture.setUseAvx2(false);
  texture.brightness(samples, portable);
  for (size_t i = 0; i < samples.size(); ++i) {
    // FMA rounding only (amplified by the hard-edge ramp); a grey level is 1/255.
    ASSERT_NEAR(avx2[i], portable[i], 2e-4f) << i;
  }
}

TEST(ProceduralTextureTest, OctavesFinerThanTwoFootprintsFadeToTheMean) {
  ProceduralTextureConfig config;
  config.contrast = 0.8;
  const ProceduralTexture texture(config);
  // A footprint of twice the coarsest wavelength hides every octave: the mean everywhere.
  const float footprint = 2.0f * static_cast<float>(config.base_wavelength_m);
  for (const auto& s : randomSamples(64, 0.0f)) {
    EXPECT_NEAR(texture.brightness(s.point, s.normal, footprint), 1.0f - 0.8f + 0.8f * 0.5f, 1e-6f);
  }
  // Seen from closer, points along a line take many different values.
  std::vector<float> values;
  for (int i = 0; i < 50; ++i) {
    values.push_back(texture.brightness({0.037f * i, 0.0f, 1.0f}, {0, 0, 1}, 0.001f));
  }
  std::sort(values.begin(), values.end());
  EXPECT_GT(std::unique(values.begin(), values.end()) - values.begin(), 20);
}

TEST(ProceduralTextureTest, RejectsInvalidConfig) {
  ProceduralTextureConfig config;
  config.octaves = 9;
  EXPECT_THROW(ProceduralTexture{config}, std::invalid_argument);
  config = ProceduralTextureConfig{};
  config.base_wavelength_m = 0.0;
  EXPECT_NE(config.validate().find("base_wavelength_m"), std::string::npos);
}

}  // namespace
}  // namespace cblox
