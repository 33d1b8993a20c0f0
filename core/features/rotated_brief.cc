#include "core/features/rotated_brief.h"

#include <cmath>

#include "core/geometry/cpu_features.h"

#if defined(__SSE2__)
#include <emmintrin.h>
#endif

// Bit-exactness with OpenCV needs x = px * a - py * b evaluated as two rounded products and a
// rounded difference: CMakeLists.txt compiles this file with -ffp-contract=off so that no
// fused multiply-add is formed even with -march=native.

namespace cblox {

RotatedBrief::RotatedBrief() {
  const auto& pattern = orbPattern31();
  for (size_t i = 0; i < pattern.size(); ++i) {
    a_x_[i] = pattern[i].a.x;
    a_y_[i] = pattern[i].a.y;
    b_x_[i] = pattern[i].b.x;
    b_y_[i] = pattern[i].b.y;
  }
}

namespace {

#if CBLOX_HAVE_X86
// Offsets (from the keypoint's pixel) of eight rotated, rounded pattern points: the same
// float operations and rounding as the SSE2 and scalar paths (no FMA: the target has none).
__attribute__((target("avx2"), always_inline)) inline __m256i rotatedOffsets8(
    const float* x, const float* y, __m256 cos_a, __m256 sin_a, __m256i step) {
  const __m256 px = _mm256_load_ps(x), py = _mm256_load_ps(y);
  const __m256 rx = _mm256_sub_ps(_mm256_mul_ps(px, cos_a), _mm256_mul_ps(py, sin_a));
  const __m256 ry = _mm256_add_ps(_mm256_mul_ps(px, sin_a), _mm256_mul_ps(py, cos_a));
  return _mm256_add_epi32(_mm256_mullo_epi32(_mm256_cvtps_epi32(ry), step), _mm256_cvtps_epi32(rx));
}

// Eight pairs at a time: both points' pixels gathered as 32-bit words (the three bytes after
// a pixel are inside the image: the keypoint is at least kRotatedBriefRadius pixels from the
// border and the pattern reaches 18, so the farthest read ends within the next row) and
// masked to their low byte.
__attribute__((target("avx2"))) OrbDescriptor briefAvx2(const uint8_t* center, int step, float a,
                                                        float b, const float* a_x, const float* a_y,
                                                        const float* b_x, const float* b_y) {
  const __m256 cos_a = _mm256_set1_ps(a), sin_a = _mm256_set1_ps(b);
  const __m256i vstep = _mm256_set1_epi32(step);
  const __m256i low_byte = _mm256_set1_epi32(0xFF);
  const int* base = reinterpret_cast<const int*>(center);
  OrbDescriptor d;
  for (size_t w = 0; w < 4; ++w) {
    uint64_t word = 0;
    for (size_t g = 0; g < 8; ++g) {
      const size_t k = w * 64 + g * 8;
      const __m256i oa = rotatedOffsets8(&a_x[k], &a_y[k], cos_a, sin_a, vstep);
      const __m256i ob = rotatedOffsets8(&b_x[k], &b_y[k], cos_a, sin_a, vstep);
      const __m256i ia = _mm256_and_si256(_mm256_i32gather_epi32(base, oa, 1), low_byte);
      const __m256i ib = _mm256_and_si256(_mm256_i32gather_epi32(base, ob, 1), low_byte);
      const unsigned bits = static_cast<unsigned>(
          _mm256_movemask_ps(_mm256_castsi256_ps(_mm256_cmpgt_epi32(ib, ia))));
      word |= static_cast<uint64_t>(bits) << (8 * g);
    }
    d.words[w] = word;
  }
  return d;
}
#endif

}  // namespace

OrbDescriptor RotatedBrief::compute(const cv::Mat& blurred_level, float x, float y,
                                    float angle_deg) const {
  return describe(blurred_level, x, y, angle_deg, cpuHasAvx2());
}

OrbDescriptor RotatedBrief::computePortable(const cv::Mat& blurred_level, float x, float y,
                                            float angle_deg) const {
  return describe(blurred_level, x, y, angle_deg, false);
}

OrbDescriptor RotatedBrief::describe(const cv::Mat& blurred_level, float x, float y,
                                     float angle_deg, bool avx2) const {
  // The same float operations as OpenCV's computeOrbDescriptors.
  const float angle = angle_deg * static_cast<float>(CV_PI / 180.f);
  const float a = std::cos(angle), b = std::sin(angle);
  const uint8_t* center = blurred_level.ptr<uint8_t>(cvRound(y)) + cvRound(x);
  const int step = static_cast<int>(blurred_level.step);
#if CBLOX_HAVE_X86
  if (avx2) {
    return briefAvx2(center, step, a, b, a_x_.data(), a_y_.data(), b_x_.data(), b_y_.data());
  }
#else
  (void)avx2;
#endif

  // Offsets of the rotated, rounded points a and b of the 256 pairs.
  alignas(16) std::array<int, kOrbPatternPairs> offset_a, offset_b;
  const auto rotate = [&](const std::array<float, kOrbPatternPairs>& px,
                          const std::array<float, kOrbPatternPairs>& py,
                          std::array<int, kOrbPatternPairs>* offset) {
#if defined(__SSE2__)
    const __m128 va = _mm_set1_ps(a), vb = _mm_set1_ps(b);
    const __m128i vstep = _mm_set1_epi32(step);
    for (size_t k = 0; k < offset->size(); k += 4) {
      const __m128 x4 = _mm_load_ps(&px[k]), y4 = _mm_load_ps(&py[k]);
      const __m128 rx = _mm_sub_ps(_mm_mul_ps(x4, va), _mm_mul_ps(y4, vb));
      const __m128 ry = _mm_add_ps(_mm_mul_ps(x4, vb), _mm_mul_ps(y4, va));
      // Round half to even (the default MXCSR mode), like cvRound's cvtss2si.
      const __m128i ix = _mm_cvtps_epi32(rx), iy = _mm_cvtps_epi32(ry);
      // iy * step with SSE2: multiply the even and odd lanes separately.
      const __m128i even = _mm_mul_epu32(iy, vstep);
      const __m128i odd = _mm_mul_epu32(_mm_srli_epi64(iy, 32), _mm_srli_epi64(vstep, 32));
      const __m128i prod = _mm_unpacklo_epi32(_mm_shuffle_epi32(even, _MM_SHUFFLE(0, 0, 2, 0)),
                                              _mm_shuffle_epi32(odd, _MM_SHUFFLE(0, 0, 2, 0)));
      _mm_store_si128(reinterpret_cast<__m128i*>(&(*offset)[k]), _mm_add_epi32(prod, ix));
    }
#else
    for (size_t k = 0; k < offset->size(); ++k) {
      const float rx = px[k] * a - py[k] * b;
      const float ry = px[k] * b + py[k] * a;
      (*offset)[k] =
          static_cast<int>(std::nearbyint(ry)) * step + static_cast<int>(std::nearbyint(rx));
    }
#endif
  };
  rotate(a_x_, a_y_, &offset_a);
  rotate(b_x_, b_y_, &offset_b);

  OrbDescriptor d;
  for (size_t w = 0; w < 4; ++w) {
    uint64_t word = 0;
    for (size_t i = 0; i < 64; ++i) {
      const size_t k = w * 64 + i;
      word |= static_cast<uint64_t>(center[offset_a[k]] < center[offset_b[k]]) << i;
    }
    d.words[w] = word;
  }
  return d;
}

}  // namespace cblox
