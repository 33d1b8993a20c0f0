#pragma once

#include <cstddef>
#include <vector>

#include <Eigen/Core>

#include "core/features/keypoint.h"
#include "core/features/orb_descriptor.h"
#include "core/tracking/feature_grid.h"
#include "core/tracking/tracking_camera.h"
#include "core/vocabulary/bow_vector.h"

namespace cblox {

/// The features of one image and what is known of their depth: the part of a frame that a
/// keyframe keeps unchanged. Index i means the same feature in every vector.
/// Built once (by the tracker), then shared read-only (std::shared_ptr<const FrameFeatures>)
/// between a frame and the keyframe made from it: const access is thread-safe.
struct FrameFeatures {
  std::vector<Keypoint> keypoints;         ///< level-0 pixels of the rectified left image
  std::vector<OrbDescriptor> descriptors;  ///< one per keypoint
  std::vector<float> right_u;              ///< stereo / virtual right u; < 0 when unknown
  std::vector<float> depth;                ///< metres along z; < 0 when unknown
  /// Stereo matching only: the disparity correction c (pixels) applied when the frame was
  /// built: right_u is the matched column minus c, and depth = bf / (u - right_u). The
  /// matched (raw) column is right_u + c. 0 for RGB-D and uncorrected frames.
  float disparity_correction_px = 0.0f;
  /// True when right_u comes from stereo matching (false: from a depth image, RGB-D).
  bool stereo_matched = false;
  FeatureGrid grid;                        ///< keypoints by image cell
  BowVector bow;                           ///< empty until computed
  FeatureVector feature_vector;            ///< empty until computed

  size_t size() const { return keypoints.size(); }
  bool hasDepth(size_t i) const { return depth[i] > 0.0f; }
  /// The camera-frame point of feature i (metres), from its depth: valid only if hasDepth(i).
  Eigen::Vector3d unproject(size_t i, const TrackingCamera& camera) const {
    const double z = depth[i];
    const PinholeIntrinsics& k = camera.intrinsics;
    return {(keypoints[i].u - k.cx) * z / k.fx, (keypoints[i].v - k.cy) * z / k.fy, z};
  }
};

}  // namespace cblox
