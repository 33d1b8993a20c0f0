#include "core/features/brief_blur.h"

#include <algorithm>
#include <array>
#include <stdexcept>

#include <opencv2/imgproc.hpp>

#include "core/geometry/cpu_features.h"

namespace cblox {
namespace {

constexpr int kRadius = 3;

// BORDER_REFLECT_101 index for n >= kRadius + 1 and i in [-kRadius, n - 1 + kRadius].
int reflect101(int i, int n) { return i < 0 ? -i : i >= n ? 2 * (n - 1) - i : i; }

#if CBLOX_HAVE_X86
// 8 bytes as 8 floats (exact).
__attribute__((target("avx2"), always_inline)) inline __m256 widen8(const uint8_t* p) {
  return _mm256_cvtepi32_ps(
      _mm256_cvtepu8_epi32(_mm_loadl_epi64(reinterpret_cast<const __m128i*>(p))));
}

// Row pass of one source row `src` (w >= 8 pixels) into `out` (w floats), 8 pixels at a time;
// the last block overlaps the previous one. The row is first converted to floats with its
// reflections (`row`, w + 6 floats), so that each tap is one multiply-add from memory. As
// OpenCV's RowVec_8u32f: s = 0, then s = fma(pixel_k, g_k, s) for the taps from left to right.
__attribute__((target("avx2,fma"))) void rowPassAvx2(const uint8_t* src, int w, const float* g,
                                                     float* row, float* out) {
  for (int next = 0; next < w;) {
    const int x = std::min(next, w - 8);
    _mm256_storeu_ps(row + kRadius + x, widen8(src + x));
    next = x + 8;
  }
  for (int i = 1; i <= kRadius; ++i) {
    row[kRadius - i] = static_cast<float>(src[i]);
    row[kRadius + w - 1 + i] = static_cast<float>(src[w - 1 - i]);
  }
  __m256 k[7];
  for (size_t i = 0; i < 7; ++i) k[i] = _mm256_set1_ps(g[i]);
  int next = 0;
  for (; next + 32 <= w; next += 32) {  // four independent chains of multiply-adds
    const float* r = row + next;
    __m256 s0 = _mm256_mul_ps(_mm256_loadu_ps(r), k[0]);
    __m256 s1 = _mm256_mul_ps(_mm256_loadu_ps(r + 8), k[0]);
    __m256 s2 = _mm256_mul_ps(_mm256_loadu_ps(r + 16), k[0]);
    __m256 s3 = _mm256_mul_ps(_mm256_loadu_ps(r + 24), k[0]);
    for (size_t i = 1; i < 7; ++i) {
      s0 = _mm256_fmadd_ps(_mm256_loadu_ps(r + i), k[i], s0);
      s1 = _mm256_fmadd_ps(_mm256_loadu_ps(r + i + 8), k[i], s1);
      s2 = _mm256_fmadd_ps(_mm256_loadu_ps(r + i + 16), k[i], s2);
      s3 = _mm256_fmadd_ps(_mm256_loadu_ps(r + i + 24), k[i], s3);
    }
    _mm256_storeu_ps(out + next, s0);
    _mm256_storeu_ps(out + next + 8, s1);
    _mm256_storeu_ps(out + next + 16, s2);
    _mm256_storeu_ps(out + next + 24, s3);
  }
  while (next < w) {
    const int x = std::min(next, w - 8);
    __m256 s = _mm256_mul_ps(_mm256_loadu_ps(row + x), k[0]);
    for (size_t i = 1; i < 7; ++i) s = _mm256_fmadd_ps(_mm256_loadu_ps(row + x + i), k[i], s);
    _mm256_storeu_ps(out + x, s);
    next = x + 8;
  }
}

__attribute__((target("avx2,fma"), always_inline)) inline __m256i column8(
    const float* const (&rows)[7], int x, __m256 k0, __m256 k1, __m256 k2, __m256 k3) {
  __m256 s = _mm256_mul_ps(_mm256_loadu_ps(rows[3] + x), k0);
  s = _mm256_fmadd_ps(_mm256_add_ps(_mm256_loadu_ps(rows[4] + x), _mm256_loadu_ps(rows[2] + x)), k1,
                      s);
  s = _mm256_fmadd_ps(_mm256_add_ps(_mm256_loadu_ps(rows[5] + x), _mm256_loadu_ps(rows[1] + x)), k2,
                      s);
  s = _mm256_fmadd_ps(_mm256_add_ps(_mm256_loadu_ps(rows[6] + x), _mm256_loadu_ps(rows[0] + x)), k3,
                      s);
  return _mm256_cvtps_epi32(s);  // round half to even (the default rounding mode)
}

__attribute__((target("avx2,fma"))) void columnPassAvx2(const float* const (&rows)[7], int w,
                                                        const float* g, uint8_t* out) {
  const __m256 k0 = _mm256_set1_ps(g[3]), k1 = _mm256_set1_ps(g[4]), k2 = _mm256_set1_ps(g[5]),
               k3 = _mm256_set1_ps(g[6]);
  for (int next = 0; next < w;) {
    const int x = std::min(next, w - 16);
    // packs interleaves by 128-bit lane (pixels 0-3, 8-11 | 4-7, 12-15): the first permutation
    // orders the 16-bit words, packus saturates them to [0, 255] (both lanes: 0-7 | 8-15) and
    // the second permutation gathers the 16 bytes.
    const __m256i words = _mm256_permute4x64_epi64(
        _mm256_packs_epi32(column8(rows, x, k0, k1, k2, k3), column8(rows, x + 8, k0, k1, k2, k3)),
        0xD8);
    const __m256i ordered = _mm256_permute4x64_epi64(_mm256_packus_epi16(words, words), 0x08);
    _mm_storeu_si128(reinterpret_cast<__m128i*>(out + x), _mm256_castsi256_si128(ordered));
    next = x + 16;
  }
}
#endif

// OpenCV's kernel for GaussianBlur(7x7, sigma 2) on 8-bit images: the normalised Gaussian in
// floats (0.0702, 0.1311, 0.1907, 0.2161, ...), from OpenCV itself.
const float* gaussianKernel() {
  static const std::array<float, 7> g = [] {
    const cv::Mat k = cv::getGaussianKernel(7, 2.0, CV_32F);
    std::array<float, 7> out{};
    for (size_t i = 0; i < out.size(); ++i) out[i] = k.at<float>(static_cast<int>(i));
    return out;
  }();
  return g.data();
}

}  // namespace

void BriefBlur::applyOpenCv(const cv::Mat& level, cv::Mat* dst) {
  if (level.empty() || level.type() != CV_8UC1) {
    throw std::invalid_argument("BriefBlur: the level must be a non-empty CV_8UC1 image");
  }
  padded_.create(level.rows + 2 * kRadius, level.cols + 2 * kRadius, CV_8UC1);
  // BORDER_ISOLATED: when `level` is a window of a bigger image, reflect it rather than
  // reading the pixels around it.
  cv::copyMakeBorder(level, padded_, kRadius, kRadius, kRadius, kRadius,
                     cv::BORDER_REFLECT_101 | cv::BORDER_ISOLATED);
  *dst = padded_(cv::Rect(kRadius, kRadius, level.cols, level.rows));
  cv::GaussianBlur(*dst, *dst, cv::Size(7, 7), 2, 2, cv::BORDER_REFLECT_101);
}

void BriefBlur::apply(const cv::Mat& level, cv::Mat* dst) {
  if (level.empty() || level.type() != CV_8UC1) {
    throw std::invalid_argument("BriefBlur: the level must be a non-empty CV_8UC1 image");
  }
  const int w = level.cols, h = level.rows;
#if CBLOX_HAVE_X86
  if (w >= 16 && h > kRadius && cpuHasAvx2Fma()) {
    const float* g = gaussianKernel();
    dst->create(h, w, CV_8UC1);
    row_.resize(static_cast<size_t>(w + 2 * kRadius));
    constexpr int kSlots = 8;  // rows y - 3 .. y + 3 are within the last 8 computed
    ring_.resize(static_cast<size_t>(kSlots) * static_cast<size_t>(w));
    const auto slot = [&](int y) {
      return ring_.data() + static_cast<size_t>(y % kSlots) * static_cast<size_t>(w);
    };
    int computed = 0;  // rows [0, computed) have their row pass in the ring
    for (int y = 0; y < h; ++y) {
      for (; computed < std::min(h, y + kRadius + 1); ++computed) {
        rowPassAvx2(level.ptr<uint8_t>(computed), w, g, row_.data(), slot(computed));
      }
      const float* const rows[7] = {slot(reflect101(y - 3, h)), slot(reflect101(y - 2, h)),
                                    slot(reflect101(y - 1, h)), slot(y),
                                    slot(reflect101(y + 1, h)), slot(reflect101(y + 2, h)),
                                    slot(reflect101(y + 3, h))};
      columnPassAvx2(rows, w, g, dst->ptr<uint8_t>(y));
    }
    return;
  }
#endif
  applyOpenCv(level, dst);
}

}  // namespace cblox
