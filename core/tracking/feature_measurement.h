#pragma once

#include <cstddef>

#include <Eigen/Core>

#include "core/features/scale_pyramid.h"
#include "core/optimization/pose_optimizer.h"
#include "core/optimization/reprojection_error.h"
#include "core/tracking/frame_features.h"

namespace cblox {

/// What feature i of `f` measures for the optimisers: its keypoint, its right-image
/// coordinate (-1 without stereo) and its level's 1/sigma^2. Thread-safe (pure).
inline StereoMeasurement featureMeasurement(const FrameFeatures& f, size_t i,
                                            const ScalePyramid& pyramid) {
  StereoMeasurement m;
  m.u = f.keypoints[i].u;
  m.v = f.keypoints[i].v;
  m.u_right = f.right_u[i];
  m.inv_sigma2 = pyramid.invSigma2(f.keypoints[i].octave);
  return m;
}

/// featureMeasurement() with a stereo-matched right column corrected by `correction_px`
/// (the disparity correction in use) instead of the one `f` was built with: the matched
/// column right_u + f.disparity_correction_px, minus correction_px. A column that would leave
/// no positive disparity makes the measurement mono; RGB-D columns are unchanged.
/// Thread-safe (pure).
inline StereoMeasurement featureMeasurement(const FrameFeatures& f, size_t i,
                                            const ScalePyramid& pyramid, float correction_px) {
  StereoMeasurement m = featureMeasurement(f, i, pyramid);
  if (!f.stereo_matched || m.u_right < 0.0 || correction_px == f.disparity_correction_px) {
    return m;
  }
  const double corrected = m.u_right + f.disparity_correction_px - correction_px;
  m.u_right = corrected >= 0.0 && corrected < m.u ? corrected : -1.0;
  return m;
}

/// Feature i of `f` observing the world point p_G: one term of a motion-only pose
/// optimisation. Thread-safe (pure).
inline PoseObservation poseObservation(const FrameFeatures& f, size_t i,
                                       const ScalePyramid& pyramid, const Eigen::Vector3d& p_G) {
  PoseObservation o;
  static_cast<StereoMeasurement&>(o) = featureMeasurement(f, i, pyramid);
  o.p_G = p_G;
  return o;
}

}  // namespace cblox
