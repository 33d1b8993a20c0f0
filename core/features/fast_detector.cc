#include "core/features/fast_detector.h"

#include <algorithm>
#include <array>
#include <stdexcept>

#include "core/geometry/cpu_features.h"

#if defined(__SSE2__)
#include <emmintrin.h>
#endif

namespace cblox {
namespace {

// The circle in OpenCV's order (makeOffsets, pattern 16): (dx, dy) pairs.
constexpr std::array<std::array<int, 2>, 16> kCircle = {{{0, 3},
                                                         {1, 3},
                                                         {2, 2},
                                                         {3, 1},
                                                         {3, 0},
                                                         {3, -1},
                                                         {2, -2},
                                                         {1, -3},
                                                         {0, -3},
                                                         {-1, -3},
                                                         {-2, -2},
                                                         {-3, -1},
                                                         {-3, 0},
                                                         {-3, 1},
                                                         {-2, 2},
                                                         {-1, 3}}};

// OpenCV's cornerScore<16>: the largest t for which the pixel is a corner at threshold t,
// i.e. max over the 16 arcs of 9 of the smallest |centre - circle| of one sign, minus one
// (never below `threshold`).
int cornerScore(const uint8_t* p, const std::array<int, 16>& offset, int threshold) {
  std::array<int, 25> d;
  const int v = p[0];
  for (size_t k = 0; k < 25; ++k) d[k] = v - p[offset[k % 16]];
  int a0 = threshold;
  for (size_t k = 0; k < 16; ++k) {
    int a = d[k];
    for (size_t j = 1; j < 9; ++j) a = std::min(a, d[k + j]);
    a0 = std::max(a0, a);  // centre brighter than the arc by at least a
  }
  int b0 = -a0;
  for (size_t k = 0; k < 16; ++k) {
    int b = d[k];
    for (size_t j = 1; j < 9; ++j) b = std::max(b, d[k + j]);
    b0 = std::min(b0, b);  // centre darker than the arc by at least -b
  }
  return -b0 - 1;
}

// Segment test of one pixel (scalar): a corner at `threshold`?
bool isCorner(const uint8_t* p, const std::array<int, 16>& offset, int threshold) {
  const int v = p[0];
  int bright_run = 0, dark_run = 0;
  for (size_t k = 0; k < 25; ++k) {  // 16 + 9: runs may wrap around
    const int q = p[offset[k % 16]];
    bright_run = q > v + threshold ? bright_run + 1 : 0;
    dark_run = q < v - threshold ? dark_run + 1 : 0;
    if (bright_run >= 9 || dark_run >= 9) return true;
  }
  return false;
}

#if defined(__SSE2__)
// The segment-test strength of the 16 pixels at `p`: for each sign, with the saturated
// differences e_k = max(0, centre - circle_k) (darker circle) or max(0, circle_k - centre)
// (brighter circle), A = max over the 16 arcs of 9 of the arc's smallest e (found by doubling:
// minima over 2, 4, 8, then 9 neighbours); the result is the larger of the two signs. A pixel
// is a corner at threshold t iff A > t, and OpenCV's score is max(t, A) - 1.
__m128i arcStrength(const __m128i (&e)[16]) {
  __m128i m2[16], m4[16];
  for (size_t k = 0; k < 16; ++k) m2[k] = _mm_min_epu8(e[k], e[(k + 1) & 15]);
  for (size_t k = 0; k < 16; ++k) m4[k] = _mm_min_epu8(m2[k], m2[(k + 2) & 15]);
  __m128i best = _mm_setzero_si128();
  for (size_t k = 0; k < 16; ++k) {
    const __m128i m9 = _mm_min_epu8(_mm_min_epu8(m4[k], m4[(k + 4) & 15]), e[(k + 8) & 15]);
    best = _mm_max_epu8(best, m9);
  }
  return best;
}

__m128i strength16(const uint8_t* p, const std::array<int, 16>& offset) {
  const __m128i v = _mm_loadu_si128(reinterpret_cast<const __m128i*>(p));
  __m128i darker[16], brighter[16];
  for (size_t k = 0; k < 16; ++k) {
    const __m128i q = _mm_loadu_si128(reinterpret_cast<const __m128i*>(p + offset[k]));
    darker[k] = _mm_subs_epu8(v, q);
    brighter[k] = _mm_subs_epu8(q, v);
  }
  return _mm_max_epu8(arcStrength(darker), arcStrength(brighter));
}

// The quick test (as OpenCV's, exact): every arc of 9 contains two neighbouring compass points
// of the circle (positions 0, 4, 8, 12), so a pixel whose arc strength exceeds t has such a
// pair both beyond t on one side. Returns the mask of the 16 pixels at `p` that have one; the
// others are not corners and need no full test.
int quickCandidates16(const uint8_t* p, const std::array<int, 16>& offset, __m128i t) {
  const __m128i v = _mm_loadu_si128(reinterpret_cast<const __m128i*>(p));
  __m128i dark[4], bright[4];
  for (size_t c = 0; c < 4; ++c) {
    const __m128i q = _mm_loadu_si128(reinterpret_cast<const __m128i*>(p + offset[4 * c]));
    dark[c] = _mm_subs_epu8(v, q);
    bright[c] = _mm_subs_epu8(q, v);
  }
  __m128i best = _mm_setzero_si128();
  for (size_t c = 0; c < 4; ++c) {
    best = _mm_max_epu8(best, _mm_min_epu8(dark[c], dark[(c + 1) & 3]));
    best = _mm_max_epu8(best, _mm_min_epu8(bright[c], bright[(c + 1) & 3]));
  }
  return ~_mm_movemask_epi8(_mm_cmpeq_epi8(_mm_subs_epu8(best, t), _mm_setzero_si128())) & 0xFFFF;
}

// Scores of the corners of row `row` (pixels 3 .. w - 4; needs w - 6 >= 16) into `scores`
// (same x indexing; non-corners untouched).
void scoreRowSse2(const uint8_t* row, int w, const std::array<int, 16>& offset, int threshold,
                  uint8_t* scores) {
  const __m128i t = _mm_set1_epi8(static_cast<char>(threshold));
  const __m128i zero = _mm_setzero_si128();
  alignas(16) uint8_t strength[16];
  for (int next = 3; next < w - 3;) {
    // The last block overlaps the previous one; its first lanes are done already.
    const int start = std::min(next, w - 3 - 16);
    const unsigned lanes = (0xFFFFu << (next - start)) & 0xFFFFu;
    if ((quickCandidates16(row + start, offset, t) & lanes) == 0) {
      next = start + 16;
      continue;
    }
    const __m128i a = strength16(row + start, offset);
    // Lanes with a > t are corners; their score is a - 1 (> threshold - 1).
    const int not_corner = _mm_movemask_epi8(_mm_cmpeq_epi8(_mm_subs_epu8(a, t), zero));
    unsigned corner = ~static_cast<unsigned>(not_corner) & lanes;
    if (corner != 0) {
      _mm_store_si128(reinterpret_cast<__m128i*>(strength), a);
      for (; corner != 0; corner &= corner - 1) {
        const int lane = __builtin_ctz(corner);
        scores[start + lane] = static_cast<uint8_t>(strength[lane] - 1);
      }
    }
    next = start + 16;
  }
}
#endif

#if CBLOX_HAVE_X86
// The same as scoreRowSse2 with 32 pixels at a time, for CPUs with AVX2 (chosen at run time;
// needs w - 6 >= 32).
__attribute__((target("avx2"))) __m256i arcStrengthAvx2(const __m256i (&e)[16]) {
  __m256i m2[16], m4[16];
  for (size_t k = 0; k < 16; ++k) m2[k] = _mm256_min_epu8(e[k], e[(k + 1) & 15]);
  for (size_t k = 0; k < 16; ++k) m4[k] = _mm256_min_epu8(m2[k], m2[(k + 2) & 15]);
  __m256i best = _mm256_setzero_si256();
  for (size_t k = 0; k < 16; ++k) {
    const __m256i m9 = _mm256_min_epu8(_mm256_min_epu8(m4[k], m4[(k + 4) & 15]), e[(k + 8) & 15]);
    best = _mm256_max_epu8(best, m9);
  }
  return best;
}

// quickCandidates16 for the 32 pixels at `p` (values `v`).
__attribute__((target("avx2"))) unsigned quickCandidates32(const uint8_t* p, __m256i v,
                                                           const std::array<int, 16>& offset,
                                                           __m256i t) {
  __m256i dark[4], bright[4];
  for (size_t c = 0; c < 4; ++c) {
    const __m256i q = _mm256_loadu_si256(reinterpret_cast<const __m256i*>(p + offset[4 * c]));
    dark[c] = _mm256_subs_epu8(v, q);
    bright[c] = _mm256_subs_epu8(q, v);
  }
  __m256i best = _mm256_setzero_si256();
  for (size_t c = 0; c < 4; ++c) {
    best = _mm256_max_epu8(best, _mm256_min_epu8(dark[c], dark[(c + 1) & 3]));
    best = _mm256_max_epu8(best, _mm256_min_epu8(bright[c], bright[(c + 1) & 3]));
  }
  return ~static_cast<unsigned>(
      _mm256_movemask_epi8(_mm256_cmpeq_epi8(_mm256_subs_epu8(best, t), _mm256_setzero_si256())));
}

__attribute__((target("avx2"))) void scoreRowAvx2(const uint8_t* row, int w,
                                                  const std::array<int, 16>& offset, int threshold,
                                                  uint8_t* scores) {
  const __m256i t = _mm256_set1_epi8(static_cast<char>(threshold));
  const __m256i zero = _mm256_setzero_si256();
  alignas(32) uint8_t strength[32];
  for (int next = 3; next < w - 3;) {
    const int start = std::min(next, w - 3 - 32);
    const uint8_t* p = row + start;
    const unsigned lanes = 0xFFFFFFFFu << (next - start);
    const __m256i v = _mm256_loadu_si256(reinterpret_cast<const __m256i*>(p));
    if ((quickCandidates32(p, v, offset, t) & lanes) == 0) {
      next = start + 32;
      continue;
    }
    __m256i darker[16], brighter[16];
    for (size_t k = 0; k < 16; ++k) {
      const __m256i q = _mm256_loadu_si256(reinterpret_cast<const __m256i*>(p + offset[k]));
      darker[k] = _mm256_subs_epu8(v, q);
      brighter[k] = _mm256_subs_epu8(q, v);
    }
    const __m256i a = _mm256_max_epu8(arcStrengthAvx2(darker), arcStrengthAvx2(brighter));
    const unsigned not_corner = static_cast<unsigned>(
        _mm256_movemask_epi8(_mm256_cmpeq_epi8(_mm256_subs_epu8(a, t), zero)));
    unsigned corner = ~not_corner & lanes;
    if (corner != 0) {
      _mm256_store_si256(reinterpret_cast<__m256i*>(strength), a);
      for (; corner != 0; corner &= corner - 1) {
        const int lane = __builtin_ctz(corner);
        scores[start + lane] = static_cast<uint8_t>(strength[lane] - 1);
      }
    }
    next = start + 32;
  }
}

#endif

}  // namespace

void FastDetector::detect(const cv::Mat& image, int threshold, std::vector<FastCorner>* corners) {
  if (image.type() != CV_8UC1) throw std::invalid_argument("FastDetector: image must be CV_8UC1");
  threshold = std::clamp(threshold, 0, 255);
  corners->clear();
  const int w = image.cols, h = image.rows;
  if (w < 7 || h < 7) return;
  const int step = static_cast<int>(image.step);
  std::array<int, 16> offset;
  for (size_t k = 0; k < 16; ++k) offset[k] = kCircle[k][0] + kCircle[k][1] * step;

  // Scores of the pixels, 0 for non-corners, in rows padded by kPad zeros on both sides so
  // that 16-wide reads around any pixel stay inside.
  constexpr int kPad = 16;
  const size_t stride = static_cast<size_t>(w) + 2 * kPad;
  scores_.assign(stride * static_cast<size_t>(h), 0);
  const auto scoreAt = [&](int x, int y) -> uint8_t& {
    return scores_[static_cast<size_t>(y) * stride + static_cast<size_t>(x + kPad)];
  };

  // 1. Segment test and score of every pixel in [3, w - 3) x [3, h - 3).
  for (int y = 3; y < h - 3; ++y) {
    const uint8_t* row = image.ptr<uint8_t>(y);
    uint8_t* score_row = &scoreAt(0, y);
#if CBLOX_HAVE_X86
    if (w - 6 >= 32 && cpuHasAvx2()) {
      scoreRowAvx2(row, w, offset, threshold, score_row);
      continue;
    }
#endif
#if defined(__SSE2__)
    if (w - 6 >= 16) {
      scoreRowSse2(row, w, offset, threshold, score_row);
      continue;
    }
#endif
    for (int x = 3; x < w - 3; ++x) {
      if (isCorner(row + x, offset, threshold)) {
        score_row[x] = static_cast<uint8_t>(cornerScore(row + x, offset, threshold));
      }
    }
  }

  // 2. Non-maximum suppression: a corner is kept when its score is strictly greater than its 8
  // neighbours' (row-major order, as cv::FAST).
  for (int y = 3; y < h - 3; ++y) {
    const uint8_t* s = &scoreAt(0, y);
    const uint8_t* up = s - stride;
    const uint8_t* down = s + stride;
#if defined(__SSE2__)
    const __m128i zero = _mm_setzero_si128();
    for (int x = 0; x < w; x += 16) {
      const __m128i v = _mm_loadu_si128(reinterpret_cast<const __m128i*>(s + x));
      const int empty = _mm_movemask_epi8(_mm_cmpeq_epi8(v, zero));
      if (empty == 0xFFFF) continue;
      const auto load = [&](const uint8_t* p) {
        return _mm_loadu_si128(reinterpret_cast<const __m128i*>(p));
      };
      __m128i m = _mm_max_epu8(load(s + x - 1), load(s + x + 1));
      m = _mm_max_epu8(m, _mm_max_epu8(load(up + x - 1), load(up + x)));
      m = _mm_max_epu8(m, _mm_max_epu8(load(up + x + 1), load(down + x - 1)));
      m = _mm_max_epu8(m, _mm_max_epu8(load(down + x), load(down + x + 1)));
      // v > m (unsigned) <=> v - m saturated is non-zero; then v > 0 too.
      int keep = ~_mm_movemask_epi8(_mm_cmpeq_epi8(_mm_subs_epu8(v, m), zero)) & 0xFFFF;
      for (; keep != 0; keep &= keep - 1) {
        const int lane = __builtin_ctz(static_cast<unsigned>(keep));
        corners->push_back({x + lane, y, s[x + lane]});
      }
    }
#else
    for (int x = 3; x < w - 3; ++x) {
      const uint8_t v = s[x];
      if (v == 0) continue;
      if (v > s[x - 1] && v > s[x + 1] && v > up[x - 1] && v > up[x] && v > up[x + 1] &&
          v > down[x - 1] && v > down[x] && v > down[x + 1]) {
        corners->push_back({x, y, v});
      }
    }
#endif
  }
}

}  // namespace cblox
