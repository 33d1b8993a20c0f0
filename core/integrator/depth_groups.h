#pragma once

#include <algorithm>
#include <cstdint>
#include <limits>

namespace cblox {

/// Splits `n` depths (any order) into groups wherever two neighbours in depth order are more
/// than `gap` apart, and calls emit(nearest, farthest) once per group, the nearest group
/// first. `d_min` and `d_max` must be the smallest and largest of the depths, gap > 0.
///
/// The groups are exactly those of sorting the depths, without sorting them where they span
/// fewer than 127 half gaps: each depth goes to the bucket floor((d - d_min) * 2 / gap),
/// which never decreases as d grows (float rounding included), and each bucket keeps its
/// nearest and farthest depth. Two depths of one bucket are less than a gap apart, so the
/// groups can split only between consecutive occupied buckets, where the farthest depth of
/// one and the nearest of the next are neighbours in depth order. Wider spans are sorted
/// (`depths` is then reordered).
template <typename Emit>
void forEachDepthGroup(float* depths, int n, float d_min, float d_max, float gap, Emit&& emit) {
  if (n <= 0) return;
  constexpr int kBuckets = 128;
  const float per_bucket = 2.0f / gap;
  if ((d_max - d_min) * per_bucket < static_cast<float>(kBuckets - 1)) {
    const int used = static_cast<int>((d_max - d_min) * per_bucket) + 1;
    float nearest[kBuckets], farthest[kBuckets];
    std::fill(nearest, nearest + used, std::numeric_limits<float>::infinity());
    std::fill(farthest, farthest + used, 0.0f);
    uint64_t occupied[2] = {0, 0};
    for (int i = 0; i < n; ++i) {
      const float d = depths[i];
      const int bucket = static_cast<int>((d - d_min) * per_bucket);
      occupied[bucket >> 6] |= uint64_t{1} << (bucket & 63);
      nearest[bucket] = std::min(nearest[bucket], d);
      farthest[bucket] = std::max(farthest[bucket], d);
    }
    bool started = false;
    float first = 0.0f, last = 0.0f;
    for (int word = 0; word < 2; ++word) {
      for (uint64_t bits = occupied[word]; bits != 0; bits &= bits - 1) {
        const int bucket = 64 * word + __builtin_ctzll(bits);
        if (!started) {
          first = nearest[bucket];
          started = true;
        } else if (nearest[bucket] - last > gap) {
          emit(first, last);
          first = nearest[bucket];
        }
        last = farthest[bucket];
      }
    }
    emit(first, last);
    return;
  }
  std::sort(depths, depths + n);
  float first = depths[0];
  for (int i = 1; i < n; ++i) {
    if (depths[i] - depths[i - 1] > gap) {
      emit(first, depths[i - 1]);
      first = depths[i];
    }
  }
  emit(first, depths[n - 1]);
}

}  // namespace cblox
