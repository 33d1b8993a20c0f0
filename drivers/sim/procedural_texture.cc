#include "drivers/sim/procedural_texture.h"

#include <algorithm>
#include <cmath>
#include <random>
#include <stdexcept>

namespace cblox {
namespace {

float smoothstep01(float t) { return t * t * (3.0f - 2.0f * t); }

/// 0 when wavelength <= 2 footprints, 1 when >= 4, smooth in between.
float octaveVisibility(float wavelength, float footprint) {
  if (footprint <= 0.0f) return 1.0f;
  const float ratio = wavelength / footprint;
  return smoothstep01(std::clamp((ratio - 2.0f) / 2.0f, 0.0f, 1.0f));
}

}  // namespace

std::string ProceduralTextureConfig::validate() const {
  if (!(base_wavelength_m > 0.0) || !std::isfinite(base_wavelength_m)) {
    return "base_wavelength_m must be > 0, got " + std::to_string(base_wavelength_m);
  }
  if (octaves < 1 || octaves > 8) return "octaves must be in [1, 8], got " + std::to_string(octaves);
  if (!(contrast >= 0.0 && contrast <= 1.0)) {
    return "contrast must be in [0, 1], got " + std::to_string(contrast);
  }
  if (!(hard_edge_share >= 0.0 && hard_edge_share <= 1.0)) {
    return "hard_edge_share must be in [0, 1], got " + std::to_string(hard_edge_share);
  }
  return {};
}

ProceduralTexture::ProceduralTexture(const ProceduralTextureConfig& config) : config_(config) {
  if (const std::string problem = config.validate(); !problem.empty()) {
    throw std::invalid_argument("ProceduralTextureConfig: " + problem);
  }
  std::mt19937 rng(config.seed);
  std::uniform_real_distribution<float> unit(0.0f, 1.0f);
  lattice_.resize(static_cast<size_t>(kLatticeSize) * kLatticeSize);
  for (float& value : lattice_) value = unit(rng);
}

float ProceduralTexture::valueNoise(float x, float y) const {
  const float fx = std::floor(x), fy = std::floor(y);
  const int ix = static_cast<int>(fx) & (kLatticeSize - 1);
  const int iy = static_cast<int>(fy) & (kLatticeSize - 1);
  const int jx = (ix + 1) & (kLatticeSize - 1);
  const int jy = (iy + 1) & (kLatticeSize - 1);
  const float tx = smoothstep01(x - fx), ty = smoothstep01(y - fy);
  const float* row0 = &lattice_[static_cast<size_t>(iy) * kLatticeSize];
  const float* row1 = &lattice_[static_cast<size_t>(jy) * kLatticeSize];
  const float a = row0[ix] + (row0[jx] - row0[ix]) * tx;
  const float b = row1[ix] + (row1[jx] - row1[ix]) * tx;
  return a + (b - a) * ty;
}

float ProceduralTexture::brightness(const Eigen::Vector3f& p, const Eigen::Vector3f& n,
                                    float footprint_m) const {
  // Tri-planar projection: drop the coordinate along the normal's dominant axis.
  const Eigen::Vector3f an = n.cwiseAbs();
  float s, t;
  float plane_offset;  // decorrelates the three projection planes
  if (an.x() >= an.y() && an.x() >= an.z()) {
    s = p.y(), t = p.z(), plane_offset = 17.0f;
  } else if (an.y() >= an.z()) {
    s = p.x(), t = p.z(), plane_offset = 71.0f;
  } else {
    s = p.x(), t = p.y(), plane_offset = 131.0f;
  }
  float wavelength = static_cast<float>(config_.base_wavelength_m);
  float amplitude = 0.5f;
  float sum = 0.0f, weight = 0.0f;
  float hard = 0.5f;
  for (int octave = 0; octave < config_.octaves; ++octave) {
    const float visible = octaveVisibility(wavelength, footprint_m);
    if (visible <= 0.0f) break;  // finer octaves are smaller still
    const float offset = plane_offset + 37.0f * static_cast<float>(octave);
    const float noise = valueNoise(s / wavelength + offset, t / wavelength - offset);
    sum += amplitude * (visible * noise + (1.0f - visible) * 0.5f);
    weight += amplitude;
    if (octave == 2) {
      // Hard-edged blobs: a steep ramp through the octave's median, as sharp as the pixel
      // footprint allows (edge width about one footprint).
      const float width = std::max(footprint_m / wavelength, 0.02f);
      hard = std::clamp((noise - 0.5f) / width + 0.5f, 0.0f, 1.0f);
      hard = visible * hard + (1.0f - visible) * 0.5f;
    }
    wavelength *= 0.5f;
    amplitude *= 0.85f;
  }
  const float smooth = weight > 0.0f ? sum / weight : 0.5f;
  // Value noise concentrates around 0.5: stretch it to use the whole range.
  const float stretched = std::clamp((smooth - 0.5f) * 2.2f + 0.5f, 0.0f, 1.0f);
  const float share = static_cast<float>(config_.hard_edge_share);
  const float value = (1.0f - share) * stretched + share * hard;
  const float contrast = static_cast<float>(config_.contrast);
  return 1.0f - contrast + contrast * value;
}

}  // namespace cblox
