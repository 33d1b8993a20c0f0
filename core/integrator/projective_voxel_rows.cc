#include "core/integrator/projective_voxel_rows.h"

#include <algorithm>
#include <cstring>

#if defined(__SSE2__)
#include <emmintrin.h>
#endif

#include "core/geometry/cpu_features.h"

namespace cblox {
namespace {

// Pixel indices are formed in float by the vectorised projections: exact below 2^24 pixels.
bool indexExactInFloat(int width, int height) {
  return static_cast<int64_t>(width) * height < (int64_t{1} << 24);
}

constexpr float kMinZ = 1e-6f;  // a voxel centre closer to the image plane projects nowhere

// One row of `count` voxel centres p_i = p0 + i * step (camera frame) projected into the
// image: z_i, and the index of the nearest pixel, or -1 when the centre is behind the
// camera or its nearest pixel is outside the image. `cx`, `cy` include the +0.5 of
// rounding, so the nearest pixel is the truncation of (u, v) once they are >= 0.
void projectRow(float fx, float fy, float cx, float cy, int width, int height,
                const Eigen::Vector3f& p0, const Eigen::Vector3f& step, int count, float* z_out,
                int32_t* pixel_out) {
  int i = 0;
#if defined(__SSE2__)
  // Four voxels at a time (the AVX2 rows form the pixel index in the same way).
  if (indexExactInFloat(width, height)) {
    const __m128 eps = _mm_set1_ps(kMinZ), zero = _mm_setzero_ps();
    const __m128 w = _mm_set1_ps(static_cast<float>(width));
    const __m128 h = _mm_set1_ps(static_cast<float>(height));
    const __m128 last_u = _mm_set1_ps(static_cast<float>(width - 1));
    const __m128 last_v = _mm_set1_ps(static_cast<float>(height - 1));
    const __m128i minus_one = _mm_set1_epi32(-1);
    for (; i + 4 <= count; i += 4) {
      const __m128 fi = _mm_setr_ps(static_cast<float>(i), static_cast<float>(i + 1),
                                    static_cast<float>(i + 2), static_cast<float>(i + 3));
      const __m128 x = _mm_add_ps(_mm_set1_ps(p0.x()), _mm_mul_ps(fi, _mm_set1_ps(step.x())));
      const __m128 y = _mm_add_ps(_mm_set1_ps(p0.y()), _mm_mul_ps(fi, _mm_set1_ps(step.y())));
      const __m128 z = _mm_add_ps(_mm_set1_ps(p0.z()), _mm_mul_ps(fi, _mm_set1_ps(step.z())));
      const __m128 inv_z = _mm_div_ps(_mm_set1_ps(1.0f), _mm_max_ps(z, eps));
      const __m128 u =
          _mm_add_ps(_mm_mul_ps(_mm_mul_ps(_mm_set1_ps(fx), x), inv_z), _mm_set1_ps(cx));
      const __m128 v =
          _mm_add_ps(_mm_mul_ps(_mm_mul_ps(_mm_set1_ps(fy), y), inv_z), _mm_set1_ps(cy));
      const __m128 inside =
          _mm_and_ps(_mm_and_ps(_mm_cmpgt_ps(z, eps),
                                _mm_and_ps(_mm_cmpge_ps(u, zero), _mm_cmpge_ps(v, zero))),
                     _mm_and_ps(_mm_cmplt_ps(u, w), _mm_cmplt_ps(v, h)));
      const __m128i ui = _mm_cvttps_epi32(_mm_min_ps(_mm_max_ps(u, zero), last_u));
      const __m128i vi = _mm_cvttps_epi32(_mm_min_ps(_mm_max_ps(v, zero), last_v));
      const __m128i pixel =
          _mm_cvttps_epi32(_mm_add_ps(_mm_mul_ps(_mm_cvtepi32_ps(vi), w), _mm_cvtepi32_ps(ui)));
      const __m128i mask = _mm_castps_si128(inside);
      _mm_storeu_si128(reinterpret_cast<__m128i*>(pixel_out + i),
                       _mm_or_si128(_mm_and_si128(mask, pixel), _mm_andnot_si128(mask, minus_one)));
      _mm_storeu_ps(z_out + i, z);
    }
  }
#endif
  for (; i < count; ++i) {
    const float fi = static_cast<float>(i);
    const float z = p0.z() + fi * step.z();
    z_out[i] = z;
    pixel_out[i] = -1;
    if (!(z > kMinZ)) continue;
    const float u = fx * (p0.x() + fi * step.x()) / z + cx;
    const float v = fy * (p0.y() + fi * step.y()) / z + cy;
    if (!(u >= 0.0f && v >= 0.0f && u < static_cast<float>(width) &&
          v < static_cast<float>(height))) {
      continue;
    }
    pixel_out[i] = static_cast<int32_t>(v) * width + static_cast<int32_t>(u);
  }
}

#if CBLOX_HAVE_X86
// Eight 12-byte voxels {distance, weight, colour} (three loads m0..m2) split into eight
// distances, weights and colour words, and back. Voxel k's three words sit at positions
// 3k, 3k + 1, 3k + 2 of m0|m1|m2; blends gather each component's words into one register
// in a fixed order and a permutation sorts them (and the inverses undo both).
struct Soa {
  __m256 distance, weight, color;
};

__attribute__((target("avx2"))) inline Soa loadVoxels(const TsdfVoxel* row) {
  const float* p = reinterpret_cast<const float*>(row);
  const __m256 m0 = _mm256_loadu_ps(p), m1 = _mm256_loadu_ps(p + 8), m2 = _mm256_loadu_ps(p + 16);
  const __m256 d = _mm256_blend_ps(_mm256_blend_ps(m0, m1, 0x92), m2, 0x24);
  const __m256 w = _mm256_blend_ps(_mm256_blend_ps(m0, m1, 0x24), m2, 0x49);
  const __m256 c = _mm256_blend_ps(_mm256_blend_ps(m0, m1, 0x49), m2, 0x92);
  return {_mm256_permutevar8x32_ps(d, _mm256_setr_epi32(0, 3, 6, 1, 4, 7, 2, 5)),
          _mm256_permutevar8x32_ps(w, _mm256_setr_epi32(1, 4, 7, 2, 5, 0, 3, 6)),
          _mm256_permutevar8x32_ps(c, _mm256_setr_epi32(2, 5, 0, 3, 6, 1, 4, 7))};
}

__attribute__((target("avx2"))) inline void storeVoxels(const Soa& v, TsdfVoxel* row) {
  const __m256 d = _mm256_permutevar8x32_ps(v.distance, _mm256_setr_epi32(0, 3, 6, 1, 4, 7, 2, 5));
  const __m256 w = _mm256_permutevar8x32_ps(v.weight, _mm256_setr_epi32(5, 0, 3, 6, 1, 4, 7, 2));
  const __m256 c = _mm256_permutevar8x32_ps(v.color, _mm256_setr_epi32(2, 5, 0, 3, 6, 1, 4, 7));
  float* p = reinterpret_cast<float*>(row);
  _mm256_storeu_ps(p, _mm256_blend_ps(_mm256_blend_ps(d, w, 0x92), c, 0x24));
  _mm256_storeu_ps(p + 8, _mm256_blend_ps(_mm256_blend_ps(d, w, 0x24), c, 0x49));
  _mm256_storeu_ps(p + 16, _mm256_blend_ps(_mm256_blend_ps(d, w, 0x49), c, 0x92));
}

// (o * a + n * b + 128) >> 8 in each 16-bit lane.
__attribute__((target("avx2"))) inline __m256i blendLanes16(__m256i o, __m256i n, __m256i a,
                                                            __m256i b) {
  return _mm256_srli_epi16(
      _mm256_add_epi16(_mm256_add_epi16(_mm256_mullo_epi16(o, a), _mm256_mullo_epi16(n, b)),
                       _mm256_set1_epi16(128)),
      8);
}

// (old * a + new * b + 128) >> 8 of every byte of each word, a + b = 256 per word. In
// 16-bit lanes: a byte times a or b is at most 255 * 256, and the sum plus 128 at most
// 255 * 256 + 128 < 2^16, so the low 16 bits of each product and sum are the exact values.
__attribute__((target("avx2"))) inline __m256i blendBytes(__m256i old_c, __m256i new_c, __m256i a,
                                                          __m256i b) {
  const __m256i zero = _mm256_setzero_si256();
  // Each word's weight in both of its 16-bit halves, then spread like the unpacked bytes
  // (unpacklo/hi_epi8 take words 0-1 / 2-3 of each 128-bit half, four bytes per word).
  const __m256i a2 = _mm256_or_si256(a, _mm256_slli_epi32(a, 16));
  const __m256i b2 = _mm256_or_si256(b, _mm256_slli_epi32(b, 16));
  const __m256i lo =
      blendLanes16(_mm256_unpacklo_epi8(old_c, zero), _mm256_unpacklo_epi8(new_c, zero),
                   _mm256_unpacklo_epi32(a2, a2), _mm256_unpacklo_epi32(b2, b2));
  const __m256i hi =
      blendLanes16(_mm256_unpackhi_epi8(old_c, zero), _mm256_unpackhi_epi8(new_c, zero),
                   _mm256_unpackhi_epi32(a2, a2), _mm256_unpackhi_epi32(b2, b2));
  return _mm256_packus_epi16(lo, hi);
}
#endif

}  // namespace

ProjectiveVoxelRows::ProjectiveVoxelRows(const Frame& frame, const TsdfVoxelUpdater& updater,
                                         bool vectorized)
    : frame_(frame),
      updater_(updater),
      cx_rounding_(frame.cx + 0.5f),
      cy_rounding_(frame.cy + 0.5f),
      vectorized_(vectorized && cpuHasAvx2() && indexExactInFloat(frame.width, frame.height)) {}

size_t ProjectiveVoxelRows::update(const Eigen::Vector3f* origins, int num_rows,
                                   const Eigen::Vector3f& step, int count,
                                   TsdfVoxel* voxels) const {
  if (vectorized_ && count % 8 == 0) return updateAvx2(origins, num_rows, step, count, voxels);
  size_t updates = 0;
  for (int r = 0; r < num_rows; ++r, voxels += count) {
    updates += updatePortable(origins[r], step, count, voxels);
  }
  return updates;
}

size_t ProjectiveVoxelRows::updatePortable(const Eigen::Vector3f& p0, const Eigen::Vector3f& step,
                                           int count, TsdfVoxel* row) const {
  float row_z[kMaxRow];
  int32_t row_pixel[kMaxRow];
  projectRow(frame_.fx, frame_.fy, cx_rounding_, cy_rounding_, frame_.width, frame_.height, p0,
             step, count, row_z, row_pixel);
  const float truncation = updater_.truncation();
  const ProjectivePixelSample* const samples = frame_.samples;
  const Color* const colors = frame_.colors;
  size_t updates = 0;
  for (int i = 0; i < count; ++i) {
    const int32_t pixel = row_pixel[i];
    if (pixel < 0) continue;
    const ProjectivePixelSample sample = samples[pixel];
    const float d = sample.depth;
    if (d <= 0.0f) continue;
    const float sdf = (d - row_z[i]) * sample.ray_factor;
    if (sdf < -truncation) continue;
    const Color c = colors != nullptr ? colors[pixel] : Color{};
    if (updater_.update(sdf, updater_.measurementWeight(d), c, row + i)) ++updates;
  }
  return updates;
}

#if CBLOX_HAVE_X86
__attribute__((target("avx2"))) size_t ProjectiveVoxelRows::updateAvx2(
    const Eigen::Vector3f* origins, int num_rows, const Eigen::Vector3f& step, int count,
    TsdfVoxel* voxels) const {
  const __m256 eps = _mm256_set1_ps(kMinZ), zero = _mm256_setzero_ps();
  const __m256 w = _mm256_set1_ps(static_cast<float>(frame_.width));
  const __m256 h = _mm256_set1_ps(static_cast<float>(frame_.height));
  const __m256 last_u = _mm256_set1_ps(static_cast<float>(frame_.width - 1));
  const __m256 last_v = _mm256_set1_ps(static_cast<float>(frame_.height - 1));
  const __m256 one = _mm256_set1_ps(1.0f);
  const __m256 truncation = _mm256_set1_ps(updater_.truncation());
  const __m256 minus_truncation = _mm256_set1_ps(-updater_.truncation());
  const __m256 minus_dropoff_start = _mm256_set1_ps(-updater_.dropoffStart());
  const __m256 dropoff_scale = _mm256_set1_ps(updater_.dropoffScale());
  const __m256 max_weight = _mm256_set1_ps(updater_.maxWeight());
  const bool dropoff = updater_.usesDropoff();
  const bool inverse_square = updater_.inverseSquareWeight();
  const ColorBlending blending = updater_.blending();
  const long long* const samples = reinterpret_cast<const long long*>(frame_.samples);
  const int* const color_words = reinterpret_cast<const int*>(frame_.colors);
  // A colour is gathered as the 4 bytes at its offset: the last pixel's would read past
  // the image, so its lanes are filled one by one.
  const int last_pixel = frame_.width * frame_.height - 1;
  const __m256i last_pixel_v = _mm256_set1_epi32(last_pixel);
  const __m256i rgb = _mm256_set1_epi32(0x00FFFFFF);
  const __m256 step_x = _mm256_set1_ps(step.x()), step_y = _mm256_set1_ps(step.y()),
               step_z = _mm256_set1_ps(step.z());
  const __m256 lanes = _mm256_setr_ps(0.0f, 1.0f, 2.0f, 3.0f, 4.0f, 5.0f, 6.0f, 7.0f);
  size_t updates = 0;
  for (int r = 0; r < num_rows; ++r, voxels += count) {
    const Eigen::Vector3f& p0 = origins[r];
    TsdfVoxel* const row = voxels;
    for (int i0 = 0; i0 < count; i0 += 8) {
      // Projection: RowProjector's arithmetic in eight lanes.
      // i0 + lane, exact in float (i0 < kMaxRow).
      const __m256 fi = _mm256_add_ps(lanes, _mm256_set1_ps(static_cast<float>(i0)));
      const __m256 x = _mm256_add_ps(_mm256_set1_ps(p0.x()), _mm256_mul_ps(fi, step_x));
      const __m256 y = _mm256_add_ps(_mm256_set1_ps(p0.y()), _mm256_mul_ps(fi, step_y));
      const __m256 z = _mm256_add_ps(_mm256_set1_ps(p0.z()), _mm256_mul_ps(fi, step_z));
      const __m256 inv_z = _mm256_div_ps(one, _mm256_max_ps(z, eps));
      const __m256 u =
          _mm256_add_ps(_mm256_mul_ps(_mm256_mul_ps(_mm256_set1_ps(frame_.fx), x), inv_z),
                        _mm256_set1_ps(cx_rounding_));
      const __m256 v =
          _mm256_add_ps(_mm256_mul_ps(_mm256_mul_ps(_mm256_set1_ps(frame_.fy), y), inv_z),
                        _mm256_set1_ps(cy_rounding_));
      const __m256 inside = _mm256_and_ps(
          _mm256_and_ps(_mm256_cmp_ps(z, eps, _CMP_GT_OQ),
                        _mm256_and_ps(_mm256_cmp_ps(u, zero, _CMP_GE_OQ),
                                      _mm256_cmp_ps(v, zero, _CMP_GE_OQ))),
          _mm256_and_ps(_mm256_cmp_ps(u, w, _CMP_LT_OQ), _mm256_cmp_ps(v, h, _CMP_LT_OQ)));
      if (_mm256_movemask_ps(inside) == 0) continue;
      const __m256i ui = _mm256_cvttps_epi32(_mm256_min_ps(_mm256_max_ps(u, zero), last_u));
      const __m256i vi = _mm256_cvttps_epi32(_mm256_min_ps(_mm256_max_ps(v, zero), last_v));
      const __m256i pixel = _mm256_cvttps_epi32(
          _mm256_add_ps(_mm256_mul_ps(_mm256_cvtepi32_ps(vi), w), _mm256_cvtepi32_ps(ui)));
      // The pixels' samples; lanes outside the image read nothing and stay 0 (no depth).
      // Each sample (depth, ray factor) is one 8-byte load: two gathers of four, then
      // the depths and ray factors are sorted out of the pairs.
      const __m256i inside_bits = _mm256_castps_si256(inside);
      const __m256i pairs_lo = _mm256_mask_i32gather_epi64(
          _mm256_setzero_si256(), samples, _mm256_castsi256_si128(pixel),
          _mm256_cvtepi32_epi64(_mm256_castsi256_si128(inside_bits)), 8);
      const __m256i pairs_hi = _mm256_mask_i32gather_epi64(
          _mm256_setzero_si256(), samples, _mm256_extracti128_si256(pixel, 1),
          _mm256_cvtepi32_epi64(_mm256_extracti128_si256(inside_bits, 1)), 8);
      const __m256 lo = _mm256_castsi256_ps(pairs_lo), hi = _mm256_castsi256_ps(pairs_hi);
      // [d0 d1 d4 d5 | d2 d3 d6 d7] -> d0..d7 (64-bit units 0, 2, 1, 3), and so for the factors.
      const __m256 d = _mm256_castpd_ps(_mm256_permute4x64_pd(
          _mm256_castps_pd(_mm256_shuffle_ps(lo, hi, _MM_SHUFFLE(2, 0, 2, 0))),
          _MM_SHUFFLE(3, 1, 2, 0)));
      const __m256 ray_factor = _mm256_castpd_ps(_mm256_permute4x64_pd(
          _mm256_castps_pd(_mm256_shuffle_ps(lo, hi, _MM_SHUFFLE(3, 1, 3, 1))),
          _MM_SHUFFLE(3, 1, 2, 0)));
      const __m256 sdf = _mm256_mul_ps(_mm256_sub_ps(d, z), ray_factor);
      // Kept: a depth, and not more than the truncation behind it (!(sdf < -truncation)).
      __m256 update = _mm256_and_ps(_mm256_and_ps(inside, _mm256_cmp_ps(d, zero, _CMP_GT_OQ)),
                                    _mm256_cmp_ps(sdf, minus_truncation, _CMP_NLT_UQ));
      if (_mm256_movemask_ps(update) == 0) continue;
      __m256 weight = inverse_square ? _mm256_div_ps(one, _mm256_mul_ps(d, d)) : one;
      if (dropoff) {
        const __m256 behind = _mm256_cmp_ps(sdf, minus_dropoff_start, _CMP_LT_OQ);
        const __m256 dropped =
            _mm256_mul_ps(weight, _mm256_mul_ps(_mm256_add_ps(truncation, sdf), dropoff_scale));
        weight = _mm256_blendv_ps(weight, dropped, behind);
        update = _mm256_andnot_ps(_mm256_and_ps(behind, _mm256_cmp_ps(weight, zero, _CMP_LE_OQ)),
                                  update);
      }
      const int update_bits = _mm256_movemask_ps(update);
      if (update_bits == 0) continue;
      updates += static_cast<size_t>(__builtin_popcount(static_cast<unsigned>(update_bits)));

      TsdfVoxel* const eight = row + i0;
      Soa voxel = loadVoxels(eight);
      const __m256 new_weight = _mm256_add_ps(voxel.weight, weight);
      const __m256 inv_new_weight = _mm256_div_ps(one, new_weight);
      const __m256 in_band = _mm256_cmp_ps(sdf, truncation, _CMP_LT_OQ);
      const __m256 measured = _mm256_blendv_ps(truncation, sdf, in_band);
      const __m256 distance = _mm256_min_ps(
          _mm256_max_ps(_mm256_mul_ps(_mm256_add_ps(_mm256_mul_ps(voxel.distance, voxel.weight),
                                                    _mm256_mul_ps(measured, weight)),
                                      inv_new_weight),
                        minus_truncation),
          truncation);
      const __m256 colour_lanes = _mm256_and_ps(update, in_band);
      if (blending != ColorBlending::kNone && _mm256_movemask_ps(colour_lanes) != 0) {
        const __m256i old_c = _mm256_castps_si256(voxel.color);
        __m256i new_c = _mm256_setzero_si256();
        if (color_words != nullptr) {
          const __m256i is_last = _mm256_cmpeq_epi32(pixel, last_pixel_v);
          const __m256i gather_lanes =
              _mm256_andnot_si256(is_last, _mm256_castps_si256(colour_lanes));
          new_c = _mm256_mask_i32gather_epi32(
              new_c, color_words, _mm256_add_epi32(pixel, _mm256_add_epi32(pixel, pixel)),
              gather_lanes, 1);
          const int last_bits =
              _mm256_movemask_ps(_mm256_and_ps(_mm256_castsi256_ps(is_last), colour_lanes));
          if (last_bits != 0) {
            alignas(32) int32_t words[8];
            _mm256_store_si256(reinterpret_cast<__m256i*>(words), new_c);
            const Color& c = frame_.colors[last_pixel];
            for (int k = 0; k < 8; ++k) {
              if (last_bits & (1 << k)) words[k] = c.r | (c.g << 8) | (c.b << 16);
            }
            new_c = _mm256_load_si256(reinterpret_cast<const __m256i*>(words));
          }
        }
        __m256i blended;
        if (blending == ColorBlending::kWeightedAverage) {
          // The new colour's share in 1/256, as TsdfVoxelUpdater::update rounds it.
          const __m256i b = _mm256_cvttps_epi32(_mm256_add_ps(
              _mm256_mul_ps(_mm256_mul_ps(weight, inv_new_weight), _mm256_set1_ps(256.0f)),
              _mm256_set1_ps(0.5f)));
          const __m256i a = _mm256_sub_epi32(_mm256_set1_epi32(256), b);
          blended = _mm256_and_si256(blendBytes(old_c, new_c, a, b), rgb);
        } else {  // kOverwrite
          blended = _mm256_and_si256(new_c, rgb);
        }
        // The padding byte is the voxel's own.
        blended = _mm256_or_si256(blended, _mm256_andnot_si256(rgb, old_c));
        voxel.color = _mm256_blendv_ps(voxel.color, _mm256_castsi256_ps(blended), colour_lanes);
      }
      voxel.distance = _mm256_blendv_ps(voxel.distance, distance, update);
      voxel.weight = _mm256_blendv_ps(voxel.weight, _mm256_min_ps(new_weight, max_weight), update);
      storeVoxels(voxel, eight);
    }
  }
  return updates;
}
#else
size_t ProjectiveVoxelRows::updateAvx2(const Eigen::Vector3f* origins, int num_rows,
                                       const Eigen::Vector3f& step, int count,
                                       TsdfVoxel* voxels) const {
  size_t updates = 0;
  for (int r = 0; r < num_rows; ++r, voxels += count) {
    updates += updatePortable(origins[r], step, count, voxels);
  }
  return updates;
}
#endif

}  // namespace cblox
