#include "drivers/sim/procedural_texture.h"

#include <algorithm>
#include <cmath>
#include <cstring>

#include <immintrin.h>
#include <random>
#include <stdexcept>

namespace cblox {

std::string ProceduralTextureConfig::validate() const {
  if (!(base_wavelength_m > 0.0) || !std::isfinite(base_wavelength_m)) {
    return "base_wavelength_m must be > 0, got " + std::to_string(base_wavelength_m);
  }
  if (octaves < 1 || octaves > 8) return "octaves must be in [1, 8], got " + std::to_string(octaves);
  if (!(persistence > 0.0 && persistence <= 2.0)) {
    return "persistence must be in (0, 2], got " + std::to_string(persistence);
  }
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
  // Rows of kLatticeStride bytes: the lattice row, then its first 4 bytes again, so the
  // right neighbour of the last column needs no wrap and a 4-byte read never leaves the row.
  lattice_.assign(static_cast<size_t>(kLatticeSize) * kLatticeStride + 4, 0);
  for (int row = 0; row < kLatticeSize; ++row) {
    uint8_t* r = &lattice_[static_cast<size_t>(row) * kLatticeStride];
    for (int col = 0; col < kLatticeSize; ++col) r[col] = static_cast<uint8_t>(byte(rng));
    for (int pad = 0; pad < 4; ++pad) r[kLatticeSize + pad] = r[pad];
  }
  use_avx2_ = __builtin_cpu_supports("avx2") && __builtin_cpu_supports("fma");
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

void ProceduralTexture::brightness(std::span<const TextureSample> samples,
                                   std::span<float> out) const {
  if (use_avx2_) {
    brightnessAvx2(samples, out);
  } else {
    brightnessPortable(samples, out);
  }
}

float ProceduralTexture::totalWeight() const {
  const float persistence = static_cast<float>(config_.persistence);
  float total = 0.0f, amplitude = 0.5f;
  for (int k = 0; k < config_.octaves; ++k, amplitude *= persistence) total += amplitude;
  return total;
}

void ProceduralTexture::prepareLanes(std::span<const TextureSample> samples, size_t start,
                                     size_t count, float* s, float* t, float* offset,
                                     float* ratio) const {
  const float base_wavelength = static_cast<float>(config_.base_wavelength_m);
  for (int l = 0; l < 8; ++l) {
    const TextureSample& x = samples[start + std::min<size_t>(static_cast<size_t>(l), count - 1)];
    // Tri-planar projection: drop the coordinate along the normal's dominant axis; each
    // plane gets its own offset so the three projections are decorrelated.
    const Eigen::Vector3f an = x.normal.cwiseAbs();
    if (an.x() >= an.y() && an.x() >= an.z()) {
      s[l] = x.point.y(), t[l] = x.point.z(), offset[l] = 17.0f;
    } else if (an.y() >= an.z()) {
      s[l] = x.point.x(), t[l] = x.point.z(), offset[l] = 71.0f;
    } else {
      s[l] = x.point.x(), t[l] = x.point.y(), offset[l] = 131.0f;
    }
    // Wavelength in pixel footprints; an octave fades out between 4 and 2 footprints.
    ratio[l] = x.footprint_m > 0.0f ? base_wavelength / x.footprint_m : 1e30f;
  }
}

// Eight samples at a time with GCC vector extensions (two SSE registers on baseline x86-64);
// the lattice reads are scalar loads.
void ProceduralTexture::brightnessPortable(std::span<const TextureSample> samples,
                                           std::span<float> out) const {
  const float base_wavelength = static_cast<float>(config_.base_wavelength_m);
  const float total_weight = totalWeight();
  const float persistence = static_cast<float>(config_.persistence);
  const float share = static_cast<float>(config_.hard_edge_share);
  const float contrast = static_cast<float>(config_.contrast);
  const size_t n = std::min(samples.size(), out.size());
  alignas(32) float s_in[kLanes], t_in[kLanes], offset_in[kLanes], ratio_in[kLanes];
  alignas(32) float result[kLanes];
  for (size_t start = 0; start < n; start += kLanes) {
    const size_t count = std::min<size_t>(kLanes, n - start);
    prepareLanes(samples, start, count, s_in, t_in, offset_in, ratio_in);
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
        for (int k = octave; k < config_.octaves; ++k, amplitude *= persistence) sum += 0.5f * amplitude;
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
      const Int8 cx0 = ix & mask, cx1 = cx0 + 1;  // the padded column needs no wrap
      const Int8 ry0 = (iy & mask) * kLatticeStride, ry1 = ((iy + 1) & mask) * kLatticeStride;
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
      amplitude *= persistence;
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

// The same computation with AVX2/FMA intrinsics: floor by vroundps, the four lattice
// corners by two 32-bit gathers (a row's byte and its right neighbour come in one dword).
[[gnu::target("avx2,fma")]] void ProceduralTexture::brightnessAvx2(
    std::span<const TextureSample> samples, std::span<float> out) const {
  const float base_wavelength = static_cast<float>(config_.base_wavelength_m);
  const float total_weight = totalWeight();
  const float persistence = static_cast<float>(config_.persistence);
  const float share = static_cast<float>(config_.hard_edge_share);
  const float contrast = static_cast<float>(config_.contrast);
  const size_t n = std::min(samples.size(), out.size());
  const int* lattice = reinterpret_cast<const int*>(lattice_.data());
  const __m256 zero = _mm256_setzero_ps(), one = _mm256_set1_ps(1.0f);
  const __m256 half = _mm256_set1_ps(0.5f), two = _mm256_set1_ps(2.0f);
  const __m256 three = _mm256_set1_ps(3.0f), inv255 = _mm256_set1_ps(1.0f / 255.0f);
  const __m256i mask = _mm256_set1_epi32(kLatticeSize - 1), byte = _mm256_set1_epi32(0xFF);
  const __m256i stride = _mm256_set1_epi32(kLatticeStride), one_i = _mm256_set1_epi32(1);
  alignas(32) float s_in[8], t_in[8], offset_in[8], ratio_in[8], result[8];
  auto smoothstep = [&](__m256 f) __attribute__((target("avx2,fma"))) {
    return _mm256_mul_ps(_mm256_mul_ps(f, f), _mm256_fnmadd_ps(two, f, three));
  };
  auto clamp01 = [&](__m256 v) __attribute__((target("avx2,fma"))) {
    return _mm256_min_ps(_mm256_max_ps(v, zero), one);
  };
  for (size_t start = 0; start < n; start += 8) {
    const size_t count = std::min<size_t>(8, n - start);
    prepareLanes(samples, start, count, s_in, t_in, offset_in, ratio_in);
    const __m256 s = _mm256_load_ps(s_in), t = _mm256_load_ps(t_in);
    const __m256 offset = _mm256_load_ps(offset_in);
    __m256 ratio = _mm256_load_ps(ratio_in);
    __m256 sum = zero, hard = half;
    float inverse_wavelength = 1.0f / base_wavelength, amplitude = 0.5f;
    for (int octave = 0; octave < config_.octaves; ++octave) {
      if (_mm256_movemask_ps(_mm256_cmp_ps(ratio, two, _CMP_GT_OQ)) == 0) {
        // This and every finer octave are at their mean everywhere.
        for (int k = octave; k < config_.octaves; ++k, amplitude *= persistence) {
          sum = _mm256_add_ps(sum, _mm256_set1_ps(0.5f * amplitude));
        }
        break;
      }
      const __m256 octave_offset = _mm256_add_ps(offset, _mm256_set1_ps(37.0f * octave));
      const __m256 inv = _mm256_set1_ps(inverse_wavelength);
      const __m256 x = _mm256_fmadd_ps(s, inv, octave_offset);
      const __m256 y = _mm256_fmsub_ps(t, inv, octave_offset);
      const __m256 x_floor = _mm256_floor_ps(x), y_floor = _mm256_floor_ps(y);
      const __m256 tx = smoothstep(_mm256_sub_ps(x, x_floor));
      const __m256 ty = smoothstep(_mm256_sub_ps(y, y_floor));
      const __m256i ix = _mm256_and_si256(_mm256_cvtps_epi32(x_floor), mask);
      const __m256i iy = _mm256_and_si256(_mm256_cvtps_epi32(y_floor), mask);
      const __m256i iy1 = _mm256_and_si256(_mm256_add_epi32(iy, one_i), mask);
      const __m256i row0 = _mm256_add_epi32(_mm256_mullo_epi32(iy, stride), ix);
      const __m256i row1 = _mm256_add_epi32(_mm256_mullo_epi32(iy1, stride), ix);
      const __m256i g0 = _mm256_i32gather_epi32(lattice, row0, 1);
      const __m256i g1 = _mm256_i32gather_epi32(lattice, row1, 1);
      const __m256 v00 = _mm256_cvtepi32_ps(_mm256_and_si256(g0, byte));
      const __m256 v01 = _mm256_cvtepi32_ps(_mm256_and_si256(_mm256_srli_epi32(g0, 8), byte));
      const __m256 v10 = _mm256_cvtepi32_ps(_mm256_and_si256(g1, byte));
      const __m256 v11 = _mm256_cvtepi32_ps(_mm256_and_si256(_mm256_srli_epi32(g1, 8), byte));
      const __m256 a = _mm256_fmadd_ps(_mm256_sub_ps(v01, v00), tx, v00);
      const __m256 b = _mm256_fmadd_ps(_mm256_sub_ps(v11, v10), tx, v10);
      const __m256 noise = _mm256_mul_ps(_mm256_fmadd_ps(_mm256_sub_ps(b, a), ty, a), inv255);
      const __m256 visible = smoothstep(clamp01(_mm256_mul_ps(_mm256_sub_ps(ratio, two), half)));
      // amplitude * (visible * noise + (1 - visible) * 0.5)
      const __m256 mixed = _mm256_fmadd_ps(visible, _mm256_sub_ps(noise, half), half);
      sum = _mm256_fmadd_ps(_mm256_set1_ps(amplitude), mixed, sum);
      if (octave == 2) {
        // Hard-edged blobs: a steep ramp through the octave's median, as sharp as the pixel
        // footprint allows (edge width about one footprint).
        const __m256 width = _mm256_max_ps(_mm256_div_ps(one, ratio), _mm256_set1_ps(0.02f));
        const __m256 h = clamp01(_mm256_add_ps(_mm256_div_ps(_mm256_sub_ps(noise, half), width), half));
        hard = _mm256_fmadd_ps(visible, _mm256_sub_ps(h, half), half);
      }
      inverse_wavelength *= 2.0f;
      ratio = _mm256_mul_ps(ratio, half);
      amplitude *= persistence;
    }
    // Value noise concentrates around 0.5: stretch it to use the whole range.
    const __m256 smooth = _mm256_div_ps(sum, _mm256_set1_ps(total_weight));
    const __m256 stretched =
        clamp01(_mm256_fmadd_ps(_mm256_sub_ps(smooth, half), _mm256_set1_ps(2.2f), half));
    const __m256 value = _mm256_fmadd_ps(_mm256_set1_ps(share), _mm256_sub_ps(hard, stretched),
                                         stretched);
    const __m256 brightness =
        _mm256_fmadd_ps(_mm256_set1_ps(contrast), value, _mm256_set1_ps(1.0f - contrast));
    _mm256_store_ps(result, brightness);
    for (size_t l = 0; l < count; ++l) out[start + l] = result[l];
  }
}

}  // namespace cblox
