#pragma once

#include <cstdint>
#include <vector>

#include "core/features/keypoint.h"

namespace cblox {

/// Keypoints bucketed into a grid of cells over the image, for "which features lie within r
/// pixels of (u, v)" queries in projection search (ORB-SLAM2 uses 64 x 48 cells).
/// Immutable after construction: const member functions are thread-safe.
class FeatureGrid {
 public:
  FeatureGrid() = default;
  /// Buckets `keypoints` (level-0 pixels) of an image of width x height pixels into
  /// cols x rows cells. Keypoints outside the image are left out.
  FeatureGrid(const std::vector<Keypoint>& keypoints, int width, int height, int cols = 64,
              int rows = 48);

  /// Indices (ascending) of the keypoints with |u_k - u| <= radius and |v_k - v| <= radius
  /// whose octave is in [min_octave, max_octave] (max_octave < 0: no upper bound).
  std::vector<uint32_t> featuresInArea(const std::vector<Keypoint>& keypoints, float u, float v,
                                       float radius, int min_octave = 0, int max_octave = -1) const;

 private:
  int cols_ = 0, rows_ = 0;
  float cell_w_ = 1.0f, cell_h_ = 1.0f;
  std::vector<std::vector<uint32_t>> cells_;
};

}  // namespace cblox
