#include "core/features/rotated_brief.h"

#include <cmath>

#include <opencv2/imgproc.hpp>

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
    px_[2 * i] = pattern[i].a.x;
    py_[2 * i] = pattern[i].a.y;
    px_[2 * i + 1] = pattern[i].b.x;
    py_[2 * i + 1] = pattern[i].b.y;
  }
}

void RotatedBrief::blurLevel(const cv::Mat& level, cv::Mat* padded, cv::Mat* dst) {
  // OpenCV's ORB blurs each level in place as a window of a bigger buffer whose border holds
  // the level's BORDER_REFLECT_101 extension. For a window (not an isolated image) OpenCV's
  // GaussianBlur takes its generic separable-filter path, which rounds differently from the
  // bit-exact path it uses for whole images; doing the same here keeps the descriptors
  // bit-identical to OpenCV's ORB.
  constexpr int kPad = 3;  // the 7x7 kernel's radius
  padded->create(level.rows + 2 * kPad, level.cols + 2 * kPad, CV_8UC1);
  cv::copyMakeBorder(level, *padded, kPad, kPad, kPad, kPad, cv::BORDER_REFLECT_101);
  *dst = (*padded)(cv::Rect(kPad, kPad, level.cols, level.rows));
  cv::GaussianBlur(*dst, *dst, cv::Size(7, 7), 2, 2, cv::BORDER_REFLECT_101);
}

OrbDescriptor RotatedBrief::compute(const cv::Mat& blurred_level, float x, float y,
                                    float angle_deg) const {
  // The same float operations as OpenCV's computeOrbDescriptors.
  const float angle = angle_deg * static_cast<float>(CV_PI / 180.f);
  const float a = std::cos(angle), b = std::sin(angle);
  const uint8_t* center = blurred_level.ptr<uint8_t>(cvRound(y)) + cvRound(x);
  const int step = static_cast<int>(blurred_level.step);

  // Offsets of the 512 rotated, rounded sample points.
  alignas(16) std::array<int, 2 * kOrbPatternPairs> offset;
#if defined(__SSE2__)
  const __m128 va = _mm_set1_ps(a), vb = _mm_set1_ps(b);
  const __m128i vstep = _mm_set1_epi32(step);
  for (size_t k = 0; k < offset.size(); k += 4) {
    const __m128 px = _mm_load_ps(&px_[k]), py = _mm_load_ps(&py_[k]);
    const __m128 rx = _mm_sub_ps(_mm_mul_ps(px, va), _mm_mul_ps(py, vb));
    const __m128 ry = _mm_add_ps(_mm_mul_ps(px, vb), _mm_mul_ps(py, va));
    // Round half to even (the default MXCSR mode), like cvRound's cvtss2si.
    const __m128i ix = _mm_cvtps_epi32(rx), iy = _mm_cvtps_epi32(ry);
    // iy * step with SSE2: multiply the even and odd lanes separately.
    const __m128i even = _mm_mul_epu32(iy, vstep);
    const __m128i odd = _mm_mul_epu32(_mm_srli_epi64(iy, 32), _mm_srli_epi64(vstep, 32));
    const __m128i prod = _mm_unpacklo_epi32(_mm_shuffle_epi32(even, _MM_SHUFFLE(0, 0, 2, 0)),
                                            _mm_shuffle_epi32(odd, _MM_SHUFFLE(0, 0, 2, 0)));
    _mm_store_si128(reinterpret_cast<__m128i*>(&offset[k]), _mm_add_epi32(prod, ix));
  }
#else
  for (size_t k = 0; k < offset.size(); ++k) {
    const float rx = px_[k] * a - py_[k] * b;
    const float ry = px_[k] * b + py_[k] * a;
    offset[k] = static_cast<int>(std::nearbyint(ry)) * step + static_cast<int>(std::nearbyint(rx));
  }
#endif

  OrbDescriptor d;
  for (size_t w = 0; w < 4; ++w) {
    uint64_t word = 0;
    const int* o = &offset[w * 128];
    for (int i = 0; i < 64; ++i) {
      word |= static_cast<uint64_t>(center[o[2 * i]] < center[o[2 * i + 1]]) << i;
    }
    d.words[w] = word;
  }
  return d;
}

}  // namespace cblox
