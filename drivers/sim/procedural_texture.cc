#include "drivers/sim/procedural_texture.h"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <random>
#include <stdexcept>

namespace cblox {

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
  std::uniform_int_distribution<int> byte(0, 255);
  lattice_.resize(static_cast<size_t>(kLatticeSize) * kLatticeSize);
  for (uint8_t& value : lattice_) value = static_cast<uint8_t>(byte(rng));
}

float ProceduralTexture::brightness(const Eigen::Vector3f& p, const Eigen::Vector3f& n,
                                    float footprint_m) const {
  const TextureSample sample{p, n, footprint_m};
  float value = 0.0f;
  brightness(std::span<const TextureSample>(&sample, 1), std::span<float>(&value, 1));
  return value;
}

namespace {

constexpr int kLanes = 8;
typedef float Float8 __attribute__((vector_size(kLanes * sizeof(float))));
typedef int32_t Int8 __attribute__((vector_size(kLanes * sizeof(int32_t))));

}  // namespace

// Eight samples at a time with GCC vector extensions (two SSE registers on baseline x86-64,
// one AVX register in the x86-64-v3 clone); the lattice gathers are scalar loads.
[[gnu::target_clones("arch=x86-64-v3", "default")]] void ProceduralTexture::brightness(
    std::span<const TextureSample> samples, std::span<float> out) const {
  const float base_wavelength = static_cast<float>(config_.base_wavelength_m);
  float total_weight = 0.0f;
  for (float k = 0, amplitude = 0.5f; k < static_cast<float>(config_.octaves); ++k, amplitude *= 0.85f) {
    total_weight += amplitude;
  }
  const float share = static_cast<float>(config_.hard_edge_share);
  const float contrast = static_cast<float>(config_.contrast);
  const size_t n = std::min(samples.size(), out.size());
  alignas(32) float s_in[kLanes], t_in[kLanes], offset_in[kLanes], ratio_in[kLanes];
  alignas(32) float result[kLanes];
  for (size_t start = 0; start < n; start += kLanes) {
    const size_t count = std::min<size_t>(kLanes, n - start);
    for (int l = 0; l < kLanes; ++l) {
      const TextureSample& x = samples[start + std::min<size_t>(static_cast<size_t>(l), count - 1)];
      // Tri-planar projection: drop the coordinate along the normal's dominant axis; each
      // plane gets its own offset so the three projections are decorrelated.
      const Eigen::Vector3f an = x.normal.cwiseAbs();
      if (an.x() >= an.y() && an.x() >= an.z()) {
        s_in[l] = x.point.y(), t_in[l] = x.point.z(), offset_in[l] = 17.0f;
      } else if (an.y() >= an.z()) {
        s_in[l] = x.point.x(), t_in[l] = x.point.z(), offset_in[l] = 71.0f;
      } else {
        s_in[l] = x.point.x(), t_in[l] = x.point.y(), offset_in[l] = 131.0f;
      }
      // Wavelength in pixel footprints; an octave fades out between 4 and 2 footprints.
      ratio_in[l] = x.footprint_m > 0.0f ? base_wavelength / x.footprint_m : 1e30f;
    }
    Float8 s, t, offset, ratio;
    std::memcpy(&s, s_in, sizeof(s));
    std::memcpy(&t, t_in, sizeof(t));
    std::memcpy(&offset, offset_in, sizeof(offset));
    std::memcpy(&ratio, ratio_in, sizeof(ratio));
    const Float8 zero = Float8{} + 0.0f, one = zero + 1.0f, half = zero + 0.5f;
    Float8 sum = zero, hard = half;
    float inverse_wavelength = 1.0f / base_wavelength, amplitude = 0.5f;
    for (int octave = 0; octave < config_.octaves; ++octave) {
      bool any_visible = false;
      for (int l = 0; l < kLanes; ++l) any_visible |= ratio[l] > 2.0f;
      if (!any_visible) {  // this and every finer octave are at their mean everywhere
        for (int k = octave; k < config_.octaves; ++k, amplitude *= 0.85f) sum += 0.5f * amplitude;
        break;
      }
      const Float8 x = s * inverse_wavelength + offset + 37.0f * static_cast<float>(octave);
      const Float8 y = t * inverse_wavelength - offset - 37.0f * static_cast<float>(octave);
      Int8 ix = __builtin_convertvector(x, Int8);
      Int8 iy = __builtin_convertvector(y, Int8);
      ix += x < __builtin_convertvector(ix, Float8);  // floor: true is -1
      iy += y < __builtin_convertvector(iy, Float8);
      const Float8 fx = x - __builtin_convertvector(ix, Float8);
      const Float8 fy = y - __builtin_convertvector(iy, Float8);
      const Float8 tx = fx * fx * (3.0f - 2.0f * fx);
      const Float8 ty = fy * fy * (3.0f - 2.0f * fy);
      const Int8 mask = Int8{} + (kLatticeSize - 1);
      const Int8 cx0 = ix & mask, cx1 = (ix + 1) & mask;
      const Int8 ry0 = (iy & mask) * kLatticeSize, ry1 = ((iy + 1) & mask) * kLatticeSize;
      const uint8_t* lattice = lattice_.data();
      // Build the corner vectors lane by lane (no round trip through memory: a wide load of
      // eight narrow stores would stall on store forwarding).
      Float8 v00, v01, v10, v11;
      for (int l = 0; l < kLanes; ++l) {
        const uint8_t* row0 = lattice + ry0[l];
        const uint8_t* row1 = lattice + ry1[l];
        v00[l] = row0[cx0[l]];
        v01[l] = row0[cx1[l]];
        v10[l] = row1[cx0[l]];
        v11[l] = row1[cx1[l]];
      }
      const Float8 a = v00 + (v01 - v00) * tx;
      const Float8 b = v10 + (v11 - v10) * tx;
      const Float8 noise = (a + (b - a) * ty) * (1.0f / 255.0f);
      Float8 ramp = (ratio - 2.0f) * 0.5f;
      ramp = ramp < zero ? zero : ramp;
      ramp = ramp > one ? one : ramp;
      const Float8 visible = ramp * ramp * (3.0f - 2.0f * ramp);
      sum += amplitude * (visible * noise + (1.0f - visible) * 0.5f);
      if (octave == 2) {
        // Hard-edged blobs: a steep ramp through the octave's median, as sharp as the pixel
        // footprint allows (edge width about one footprint).
        Float8 width = 1.0f / ratio;
        width = width < 0.02f ? zero + 0.02f : width;
        Float8 h = (noise - 0.5f) / width + 0.5f;
        h = h < zero ? zero : h;
        h = h > one ? one : h;
        hard = visible * h + (1.0f - visible) * 0.5f;
      }
      inverse_wavelength *= 2.0f;
      ratio *= 0.5f;
      amplitude *= 0.85f;
    }
    // Value noise concentrates around 0.5: stretch it to use the whole range.
    Float8 stretched = (sum / total_weight - 0.5f) * 2.2f + 0.5f;
    stretched = stretched < zero ? zero : stretched;
    stretched = stretched > one ? one : stretched;
    const Float8 value = (1.0f - share) * stretched + share * hard;
    const Float8 brightness = (1.0f - contrast) + contrast * value;
    std::memcpy(result, &brightness, sizeof(result));
    for (size_t l = 0; l < count; ++l) out[start + l] = result[l];
  }
}

}  // namespace cblox
