#pragma once

#include <memory>
#include <vector>

#include "core/features/scale_pyramid.h"
#include "core/optimization/bundle_adjustment.h"
#include "core/tracking/keyframe.h"
#include "core/tracking/landmark.h"
#include "core/tracking/sparse_map.h"
#include "core/tracking/tracking_camera.h"

namespace cblox {

/// The bundle-adjustment problem of the whole sparse map, as global BA and the covariance
/// service see it, with the map objects behind each of its entries.
struct MapBaProblem {
  /// Keyframes in map order (BaKeyframe::id = Keyframe::id); landmarks with at least one
  /// observation by those keyframes (BaLandmark::id = Landmark::id); every such observation
  /// (featureMeasurement: stereo where the feature has a right coordinate).
  BundleAdjustmentProblem problem;
  /// problem.keyframes[k] is keyframes[k]; problem.landmarks[l] is landmarks[l] (kept alive).
  std::vector<Keyframe*> keyframes;
  std::vector<std::shared_ptr<Landmark>> landmarks;
  /// SparseMap::changeIndex() when the problem was read (a later one means it is stale).
  int change_index = 0;
};

/// Reads the whole map under its shared lock (so the problem is one consistent state).
/// `fixed` is the only keyframe held fixed: the gauge; null = the keyframe with the smallest
/// id (the map's first). Thread-safe (takes
/// map.mutex() shared; call without holding it).
MapBaProblem buildMapBaProblem(const SparseMap& map, const TrackingCamera& camera,
                               const ScalePyramid& pyramid, const Keyframe* fixed);

}  // namespace cblox
