#include "core/features/orb_orientation.h"

#include <cmath>
#include <cstdlib>

#if defined(__SSE2__)
#include <emmintrin.h>
#endif

namespace cblox {

OrbOrientation::OrbOrientation() {
  // Row extents of the discrete circle of radius 15, made symmetric about the diagonal (the
  // construction of OpenCV's ORB and ORB-SLAM2, so the moments, hence angles, equal theirs).
  constexpr int kR = kOrbHalfPatchSize;
  const int vmax = cvFloor(kR * std::sqrt(2.f) / 2 + 1);
  const int vmin = cvCeil(kR * std::sqrt(2.f) / 2);
  const double r2 = static_cast<double>(kR) * kR;
  for (int v = 0; v <= vmax; ++v) {
    umax_[static_cast<size_t>(v)] = cvRound(std::sqrt(r2 - v * v));
  }
  for (int v = kR, v0 = 0; v >= vmin; --v) {
    while (umax_[static_cast<size_t>(v0)] == umax_[static_cast<size_t>(v0 + 1)]) ++v0;
    umax_[static_cast<size_t>(v)] = v0;
    ++v0;
  }
  // Lane k of the "lo" half-row is u = k - 15, of the "hi" half-row u = k (its u = 0 lane is
  // the lo half's).
  for (size_t v = 0; v <= static_cast<size_t>(kR); ++v) {
    const int d = umax_[v];
    for (int k = 0; k < 16; ++k) {
      mask_lo_[v][static_cast<size_t>(k)] = std::abs(k - kR) <= d ? 0xFF : 0;
      mask_hi_[v][static_cast<size_t>(k)] = k > 0 && k <= d ? 0xFF : 0;
    }
  }
}

float OrbOrientation::angleDeg(const cv::Mat& level, int x, int y) const {
  const uint8_t* center = level.ptr<uint8_t>(y) + x;
  const int step = static_cast<int>(level.step1());
  int m01 = 0, m10 = 0;
#if defined(__SSE2__)
  // The same integer sums, 16 pixels at a time: each row of the patch is read as u in
  // [-15, 0] ("lo") and [0, 15] ("hi", its u = 0 lane masked off), never outside the patch;
  // lanes beyond the row's extent are masked to zero. madd gives u * pixel and v * pixel in
  // 32 bits; the sums are of the same terms as the scalar loop, so equal to them exactly.
  const __m128i zero = _mm_setzero_si128();
  const __m128i u_lo0 = _mm_setr_epi16(-15, -14, -13, -12, -11, -10, -9, -8);
  const __m128i u_lo1 = _mm_setr_epi16(-7, -6, -5, -4, -3, -2, -1, 0);
  const __m128i u_hi0 = _mm_setr_epi16(0, 1, 2, 3, 4, 5, 6, 7);
  const __m128i u_hi1 = _mm_setr_epi16(8, 9, 10, 11, 12, 13, 14, 15);
  __m128i acc10 = zero, acc01 = zero;
  // Adds u * p to acc10 and w * p to acc01 for the 16 pixels p (bytes) of one half-row.
  const auto accumulate = [&](__m128i pixels, __m128i u0, __m128i u1, __m128i w) {
    const __m128i p0 = _mm_unpacklo_epi8(pixels, zero), p1 = _mm_unpackhi_epi8(pixels, zero);
    acc10 = _mm_add_epi32(acc10, _mm_add_epi32(_mm_madd_epi16(p0, u0), _mm_madd_epi16(p1, u1)));
    acc01 = _mm_add_epi32(acc01, _mm_add_epi32(_mm_madd_epi16(p0, w), _mm_madd_epi16(p1, w)));
  };
  const auto load = [](const uint8_t* p, const Mask& mask) {
    return _mm_and_si128(_mm_loadu_si128(reinterpret_cast<const __m128i*>(p)),
                         _mm_load_si128(reinterpret_cast<const __m128i*>(mask.data())));
  };
  for (int v = -kOrbHalfPatchSize; v <= kOrbHalfPatchSize; ++v) {
    const size_t row = static_cast<size_t>(std::abs(v));
    const uint8_t* r = center + v * step;
    const __m128i w = _mm_set1_epi16(static_cast<int16_t>(v));
    accumulate(load(r - kOrbHalfPatchSize, mask_lo_[row]), u_lo0, u_lo1, w);
    accumulate(load(r, mask_hi_[row]), u_hi0, u_hi1, w);
  }
  const auto total = [](__m128i a) {
    a = _mm_add_epi32(a, _mm_shuffle_epi32(a, _MM_SHUFFLE(1, 0, 3, 2)));
    a = _mm_add_epi32(a, _mm_shuffle_epi32(a, _MM_SHUFFLE(2, 3, 0, 1)));
    return _mm_cvtsi128_si32(a);
  };
  m10 = total(acc10);
  m01 = total(acc01);
#else
  for (int u = -kOrbHalfPatchSize; u <= kOrbHalfPatchSize; ++u) m10 += u * center[u];
  for (int v = 1; v <= kOrbHalfPatchSize; ++v) {
    const uint8_t* plus = center + v * step;
    const uint8_t* minus = center - v * step;
    const int d = umax_[static_cast<size_t>(v)];
    int v_sum = 0;
    for (int u = -d; u <= d; ++u) {
      const int p = plus[u], m = minus[u];
      v_sum += p - m;
      m10 += u * (p + m);
    }
    m01 += v * v_sum;
  }
#endif
  return cv::fastAtan2(static_cast<float>(m01), static_cast<float>(m10));
}

}  // namespace cblox
