#include "core/tracking/map_ba_problem.h"

#include <map>
#include <mutex>
#include <shared_mutex>

#include "core/tracking/feature_measurement.h"

namespace cblox {

MapBaProblem buildMapBaProblem(const SparseMap& map, const TrackingCamera& camera,
                               const ScalePyramid& pyramid, const Keyframe* fixed) {
  MapBaProblem out;
  BundleAdjustmentProblem& problem = out.problem;
  problem.camera = StereoCameraModel{camera.intrinsics.fx, camera.intrinsics.fy,
                                     camera.intrinsics.cx, camera.intrinsics.cy, camera.bf()};
  std::shared_lock<std::shared_mutex> lock(map.mutex());
  out.change_index = map.changeIndex();
  std::map<const Keyframe*, int> index_of;
  const std::vector<Keyframe*> keyframes = map.keyframes();
  if (fixed == nullptr) {
    for (const Keyframe* k : keyframes) {
      if (fixed == nullptr || k->id < fixed->id) fixed = k;
    }
  }
  for (Keyframe* k : keyframes) {
    index_of[k] = static_cast<int>(out.keyframes.size());
    out.keyframes.push_back(k);
    problem.keyframes.push_back(BaKeyframe{static_cast<uint64_t>(k->id), k->T_C_G(), k == fixed});
  }
  for (Landmark* l : map.landmarks()) {
    const int li = static_cast<int>(out.landmarks.size());
    bool any = false;
    for (const auto& [k, index] : l->observations()) {
      const auto it = index_of.find(k);
      if (it == index_of.end()) continue;
      BaObservation o;
      o.keyframe = it->second;
      o.landmark = li;
      static_cast<StereoMeasurement&>(o) = featureMeasurement(k->features(), index, pyramid,
                                                                 map.disparityCorrectionPx());
      problem.observations.push_back(o);
      any = true;
    }
    if (!any) continue;
    out.landmarks.push_back(l->shared_from_this());
    problem.landmarks.push_back(BaLandmark{l->id, l->position()});
  }
  return out;
}

}  // namespace cblox
