#include "core/tracking/landmark_fusion.h"

#include <limits>
#include <memory>

#include "core/tracking/feature_matcher.h"

namespace cblox {

std::vector<std::shared_ptr<Landmark>> holdLandmarks(const std::vector<Landmark*>& landmarks) {
  std::vector<std::shared_ptr<Landmark>> held;
  held.reserve(landmarks.size());
  for (Landmark* l : landmarks) {
    if (l != nullptr && !l->bad()) held.push_back(l->shared_from_this());
  }
  return held;
}

int fuseLandmarks(SparseMap* map, Keyframe* keyframe,
                  const std::vector<std::shared_ptr<Landmark>>& landmarks, float th,
                  const TrackingCamera& camera, const ScalePyramid& pyramid) {
  const FrameFeatures& f = keyframe->features();
  int fused = 0;
  for (const std::shared_ptr<Landmark>& landmark : landmarks) {
    if (landmark == nullptr || landmark->bad() || landmark->indexIn(keyframe) >= 0) continue;
    const auto p = projectLandmark(landmark.get(), keyframe->T_C_G(), camera, pyramid, 0.5f);
    if (!p) continue;
    const float radius = th * pyramid.scale(p->level);
    const std::vector<uint32_t> candidates = f.grid.featuresInArea(f.keypoints, p->u, p->v, radius);
    int best_distance = std::numeric_limits<int>::max();
    int best = -1;
    for (const uint32_t i : candidates) {
      const Keypoint& k = f.keypoints[i];
      if (k.octave < p->level - 1 || k.octave > p->level) continue;
      const float eu = p->u - k.u, ev = p->v - k.v;
      float e2 = eu * eu + ev * ev;
      float threshold = 5.991f;
      if (f.right_u[i] >= 0.0f) {
        const float er = p->u_right - f.right_u[i];
        e2 += er * er;
        threshold = 7.8f;
      }
      if (e2 * pyramid.invSigma2(k.octave) > threshold) continue;
      const int d = hammingDistance(landmark->descriptor(), f.descriptors[i]);
      if (d < best_distance) {
        best_distance = d;
        best = static_cast<int>(i);
      }
    }
    if (best < 0 || best_distance > kOrbDistanceLow) continue;
    const uint32_t index = static_cast<uint32_t>(best);
    Landmark* existing = keyframe->landmark(index);
    if (existing != nullptr && !existing->bad()) {
      if (existing->numObservations() > landmark->numObservations()) {
        map->replaceLandmark(landmark.get(), existing);
      } else {
        map->replaceLandmark(existing, landmark.get());
      }
    } else {
      SparseMap::addObservation(keyframe, index, landmark.get());
    }
    ++fused;
  }
  return fused;
}

}  // namespace cblox
