#include "core/integrator/ray_point_screen.h"

#include <cfloat>
#include <cmath>

#include "core/geometry/cpu_features.h"
#include "core/tsdf/block_index.h"

namespace cblox {
namespace {

// Finite: |v| <= FLT_MAX (false for NaN and infinities), as the AVX2 path compares.
inline bool isFiniteValue(float v) { return std::fabs(v) <= FLT_MAX; }

}  // namespace

RayPointScreen::RayPointScreen(const Frame& frame, bool vectorized)
    : frame_(frame),
      origin_in_range_(frame.t_G_C.cwiseAbs().maxCoeff() < frame.coordinate_limit),
      vectorized_(vectorized && cpuHasAvx2()) {}

size_t RayPointScreen::screen(const Eigen::Vector3f* points, uint32_t first_index, size_t count,
                              ScreenedPoint* accepted, IntegrationStats* stats) const {
#if CBLOX_HAVE_X86
  if (vectorized_) return screenAvx2(points, first_index, count, accepted, stats);
#endif
  return screenPortable(points, first_index, count, accepted, stats);
}

size_t RayPointScreen::screenPortable(const Eigen::Vector3f* points, uint32_t first_index,
                                      size_t count, ScreenedPoint* accepted,
                                      IntegrationStats* stats) const {
  const Eigen::Matrix3f& R = frame_.R_G_C;
  const Eigen::Vector3f& t = frame_.t_G_C;
  const float limit = frame_.coordinate_limit;
  size_t n = 0;
  for (size_t i = 0; i < count; ++i) {
    const float x = points[i].x(), y = points[i].y(), z = points[i].z();
    if (!isFiniteValue(x) || !isFiniteValue(y) || !isFiniteValue(z)) {
      ++stats->points_invalid;
      continue;
    }
    const float length_squared = (x * x + y * y) + z * z;
    if (length_squared < frame_.min_length_squared || length_squared > frame_.max_length_squared) {
      ++stats->points_out_of_range;
      continue;
    }
    const float gx = ((R(0, 0) * x + R(0, 1) * y) + R(0, 2) * z) + t.x();
    const float gy = ((R(1, 0) * x + R(1, 1) * y) + R(1, 2) * z) + t.y();
    const float gz = ((R(2, 0) * x + R(2, 1) * y) + R(2, 2) * z) + t.z();
    // Rays whose ends fall outside the packable grid (absurd poses) are rejected whole.
    if (!origin_in_range_ ||
        !(std::fabs(gx) < limit && std::fabs(gy) < limit && std::fabs(gz) < limit)) {
      ++stats->points_invalid;
      continue;
    }
    const float s = frame_.cell_size_inv;
    accepted[n++] = {
        first_index + static_cast<uint32_t>(i),
        packGridIndex(GridIndex(fastFloor(gx * s), fastFloor(gy * s), fastFloor(gz * s)))};
  }
  return n;
}

#if CBLOX_HAVE_X86
namespace {

// Eight consecutive Vector3f (24 floats) as x, y and z vectors, lane i = point i.
__attribute__((target("avx2"))) inline void loadPoints(const Eigen::Vector3f* points, __m256* x,
                                                       __m256* y, __m256* z) {
  const float* p = points[0].data();
  // m03 = p0 p1 | p12 p13..., i.e. lanes 0-3 hold floats 0-3 and 12-15, and so on.
  const __m256 m03 =
      _mm256_insertf128_ps(_mm256_castps128_ps256(_mm_loadu_ps(p)), _mm_loadu_ps(p + 12), 1);
  const __m256 m14 =
      _mm256_insertf128_ps(_mm256_castps128_ps256(_mm_loadu_ps(p + 4)), _mm_loadu_ps(p + 16), 1);
  const __m256 m25 =
      _mm256_insertf128_ps(_mm256_castps128_ps256(_mm_loadu_ps(p + 8)), _mm_loadu_ps(p + 20), 1);
  const __m256 xy = _mm256_shuffle_ps(m14, m25, _MM_SHUFFLE(2, 1, 3, 2));
  const __m256 yz = _mm256_shuffle_ps(m03, m14, _MM_SHUFFLE(1, 0, 2, 1));
  *x = _mm256_shuffle_ps(m03, xy, _MM_SHUFFLE(2, 0, 3, 0));
  *y = _mm256_shuffle_ps(yz, xy, _MM_SHUFFLE(3, 1, 2, 0));
  *z = _mm256_shuffle_ps(yz, m25, _MM_SHUFFLE(3, 0, 3, 1));
}

// ((r0 * x + r1 * y) + r2 * z) + t, as the portable loop rounds it.
__attribute__((target("avx2"))) inline __m256 transformRow(float r0, float r1, float r2, float t,
                                                           __m256 x, __m256 y, __m256 z) {
  const __m256 sum =
      _mm256_add_ps(_mm256_mul_ps(_mm256_set1_ps(r0), x), _mm256_mul_ps(_mm256_set1_ps(r1), y));
  return _mm256_add_ps(_mm256_add_ps(sum, _mm256_mul_ps(_mm256_set1_ps(r2), z)), _mm256_set1_ps(t));
}

// floor(g * s) minus kGridIndexMin, as unsigned 21-bit fields (valid lanes only).
__attribute__((target("avx2"))) inline __m256i cellField(__m256 g, __m256 s) {
  const __m256i index = _mm256_cvttps_epi32(_mm256_floor_ps(_mm256_mul_ps(g, s)));
  return _mm256_and_si256(_mm256_sub_epi32(index, _mm256_set1_epi32(kGridIndexMin)),
                          _mm256_set1_epi32((1 << kGridIndexBits) - 1));
}

// x | y << 21 | z << 42 for the four lanes of 32-bit fields in `x`, `y`, `z`.
__attribute__((target("avx2"))) inline __m256i packFields(__m128i x, __m128i y, __m128i z) {
  const __m256i x64 = _mm256_cvtepu32_epi64(x);
  const __m256i y64 = _mm256_slli_epi64(_mm256_cvtepu32_epi64(y), kGridIndexBits);
  const __m256i z64 = _mm256_slli_epi64(_mm256_cvtepu32_epi64(z), 2 * kGridIndexBits);
  return _mm256_or_si256(x64, _mm256_or_si256(y64, z64));
}

}  // namespace

__attribute__((target("avx2"))) size_t RayPointScreen::screenAvx2(const Eigen::Vector3f* points,
                                                                  uint32_t first_index,
                                                                  size_t count,
                                                                  ScreenedPoint* accepted,
                                                                  IntegrationStats* stats) const {
  const Eigen::Matrix3f& R = frame_.R_G_C;
  const Eigen::Vector3f& t = frame_.t_G_C;
  const __m256 abs_mask = _mm256_castsi256_ps(_mm256_set1_epi32(0x7fffffff));
  const __m256 max_finite = _mm256_set1_ps(FLT_MAX);
  const __m256 min_length_squared = _mm256_set1_ps(frame_.min_length_squared);
  const __m256 max_length_squared = _mm256_set1_ps(frame_.max_length_squared);
  const __m256 limit = _mm256_set1_ps(frame_.coordinate_limit);
  const __m256 cell_size_inv = _mm256_set1_ps(frame_.cell_size_inv);
  const unsigned origin_mask = origin_in_range_ ? 0xffu : 0u;
  size_t n = 0, invalid = 0, out_of_range = 0;
  size_t i = 0;
  for (; i + 8 <= count; i += 8) {
    __m256 x, y, z;
    loadPoints(points + i, &x, &y, &z);
    const __m256 finite = _mm256_and_ps(
        _mm256_and_ps(_mm256_cmp_ps(_mm256_and_ps(x, abs_mask), max_finite, _CMP_LE_OQ),
                      _mm256_cmp_ps(_mm256_and_ps(y, abs_mask), max_finite, _CMP_LE_OQ)),
        _mm256_cmp_ps(_mm256_and_ps(z, abs_mask), max_finite, _CMP_LE_OQ));
    const __m256 length_squared =
        _mm256_add_ps(_mm256_add_ps(_mm256_mul_ps(x, x), _mm256_mul_ps(y, y)), _mm256_mul_ps(z, z));
    const __m256 in_range =
        _mm256_and_ps(_mm256_cmp_ps(length_squared, min_length_squared, _CMP_GE_OQ),
                      _mm256_cmp_ps(length_squared, max_length_squared, _CMP_LE_OQ));
    const __m256 gx = transformRow(R(0, 0), R(0, 1), R(0, 2), t.x(), x, y, z);
    const __m256 gy = transformRow(R(1, 0), R(1, 1), R(1, 2), t.y(), x, y, z);
    const __m256 gz = transformRow(R(2, 0), R(2, 1), R(2, 2), t.z(), x, y, z);
    const __m256 in_grid =
        _mm256_and_ps(_mm256_and_ps(_mm256_cmp_ps(_mm256_and_ps(gx, abs_mask), limit, _CMP_LT_OQ),
                                    _mm256_cmp_ps(_mm256_and_ps(gy, abs_mask), limit, _CMP_LT_OQ)),
                      _mm256_cmp_ps(_mm256_and_ps(gz, abs_mask), limit, _CMP_LT_OQ));
    const unsigned finite_bits = static_cast<unsigned>(_mm256_movemask_ps(finite));
    const unsigned range_bits = finite_bits & static_cast<unsigned>(_mm256_movemask_ps(in_range));
    const unsigned accept_bits =
        range_bits & static_cast<unsigned>(_mm256_movemask_ps(in_grid)) & origin_mask;
    invalid += static_cast<size_t>(8 - __builtin_popcount(finite_bits) +
                                   __builtin_popcount(range_bits & ~accept_bits));
    out_of_range += static_cast<size_t>(__builtin_popcount(finite_bits & ~range_bits));
    if (accept_bits == 0) continue;
    const __m256i fx = cellField(gx, cell_size_inv);
    const __m256i fy = cellField(gy, cell_size_inv);
    const __m256i fz = cellField(gz, cell_size_inv);
    alignas(32) uint64_t cells[8];
    _mm256_store_si256(reinterpret_cast<__m256i*>(cells),
                       packFields(_mm256_castsi256_si128(fx), _mm256_castsi256_si128(fy),
                                  _mm256_castsi256_si128(fz)));
    _mm256_store_si256(reinterpret_cast<__m256i*>(cells + 4),
                       packFields(_mm256_extracti128_si256(fx, 1), _mm256_extracti128_si256(fy, 1),
                                  _mm256_extracti128_si256(fz, 1)));
    for (unsigned bits = accept_bits; bits != 0; bits &= bits - 1) {
      const int lane = __builtin_ctz(bits);
      accepted[n++] = {first_index + static_cast<uint32_t>(i + static_cast<size_t>(lane)),
                       cells[lane]};
    }
  }
  stats->points_invalid += invalid;
  stats->points_out_of_range += out_of_range;
  return n + screenPortable(points + i, first_index + static_cast<uint32_t>(i), count - i,
                            accepted + n, stats);
}
#endif

}  // namespace cblox
