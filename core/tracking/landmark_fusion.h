#pragma once

#include <memory>
#include <vector>

#include "core/features/scale_pyramid.h"
#include "core/tracking/sparse_map.h"
#include "core/tracking/tracking_camera.h"

namespace cblox {

/// ORB-SLAM2's ORBmatcher::Fuse: projects `landmarks` into `keyframe` and, for each, finds
/// the best feature (descriptor distance <= kOrbDistanceLow) within th * scale(level) pixels
/// of its projection whose keypoint agrees with the projection (chi2 of the 2 or 3
/// residuals, in the keypoint level's sigma, below 5.991 / 7.8). If that feature already
/// observes a landmark, the one with fewer observations is replaced by the other
/// (duplicates merge); otherwise the feature becomes a new observation of the landmark.
/// Landmarks already observed by the keyframe, bad ones, and those outside the keyframe's
/// image, distance range or viewing cone (60 degrees) are skipped. Returns the number of
/// landmarks fused or added. Needs the map's exclusive lock.
/// The candidates are held by the caller: a fusion may retire a landmark (the map drops it),
/// and a held one stays valid, and bad, for the rest of this call and for the caller's next
/// calls with the same list (the loop closer fuses one list into several keyframes; raw
/// pointers there once dangled: a use after free in cblox-bench-slam on the town).
int fuseLandmarks(SparseMap* map, Keyframe* keyframe,
                  const std::vector<std::shared_ptr<Landmark>>& landmarks, float th,
                  const TrackingCamera& camera, const ScalePyramid& pyramid);

/// The held candidates of fuseLandmarks: every non-null, not bad landmark of `landmarks`.
std::vector<std::shared_ptr<Landmark>> holdLandmarks(const std::vector<Landmark*>& landmarks);

}  // namespace cblox
