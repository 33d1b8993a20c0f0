#pragma once

namespace cblox {

/// A feature detected at one level of a scale pyramid, in the coordinates of the full-
/// resolution (level 0) image: pixel centres at integer coordinates, u to the right, v down.
/// Images given to the tracker are rectified, so keypoints need no undistortion.
/// Value type; thread-safe.
struct Keypoint {
  float u = 0.0f;          ///< column in level-0 pixels
  float v = 0.0f;          ///< row in level-0 pixels
  float angle_deg = 0.0f;  ///< orientation (intensity centroid), degrees in [0, 360)
  float response = 0.0f;   ///< FAST corner score (higher is stronger)
  int octave = 0;          ///< pyramid level the feature was detected at (0 = full size)
};

}  // namespace cblox
