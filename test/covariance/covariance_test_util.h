#pragma once

#include <vector>

#include <Eigen/Core>

#include "core/covariance/conditional_covariance.h"
#include "core/covariance/reduced_camera_matrix.h"
#include "core/optimization/ba_linearization.h"
#include "test/covariance/loop_scene.h"
#include "test/optimization/synthetic_scenes.h"

namespace cblox::test {

/// ||a - b||_F / ||b||_F.
template <typename A, typename B>
double relativeError(const A& a, const B& b) {
  return (a - b).norm() / b.norm();
}

/// makeBaScene with exact observations and keyframe 0 (id 100) fixed, linearised at the
/// true state.
inline BaScene smallGaugedScene(int keyframes, int landmarks, std::uint32_t seed) {
  BaSceneOptions o;
  o.keyframes = keyframes;
  o.landmarks = landmarks;
  o.seed = seed;
  BaScene scene = makeBaScene(o);
  scene.problem.keyframes[0].fixed = true;
  return scene;
}

/// S of a small two-lap loop scene (20 landmarks per keyframe), linearised at the truth.
inline ReducedCameraMatrix loopS(int keyframes) {
  LoopSceneOptions o;
  o.keyframes = keyframes;
  o.landmarks_per_keyframe = 20;
  const BaScene scene = makeLoopBaScene(o);
  return reduceCameraMatrix(linearizeBundleAdjustment(scene.problem, {}));
}

/// Every ordered pair (i, j), i != j, of S's keyframes.
inline std::vector<KeyframePair> allPairs(const ReducedCameraMatrix& S) {
  std::vector<KeyframePair> pairs;
  for (const std::uint64_t i : S.keyframe_ids) {
    for (const std::uint64_t j : S.keyframe_ids) {
      if (i != j) pairs.push_back({i, j});
    }
  }
  return pairs;
}

}  // namespace cblox::test
