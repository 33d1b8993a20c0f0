#include "core/maintenance/fusion_scheduler_state.h"

#include <cmath>
#include <utility>

namespace cblox {

std::string FusionSchedulerState::validate() const {
  for (size_t i = 0; i < subvolumes.size(); ++i) {
    const SubvolumeLandmarks& s = subvolumes[i];
    const std::string at = "subvolume " + std::to_string(s.subvolume) + ": ";
    if (i > 0 && s.subvolume <= subvolumes[i - 1].subvolume) {
      return at + "subvolume ids do not strictly increase";
    }
    for (size_t f = 0; f < s.keyframes.size(); ++f) {
      const KeyframeLandmarks& k = s.keyframes[f];
      const std::string in = at + "keyframe " + std::to_string(k.keyframe) + ": ";
      if (k.keyframe < 0 && k.keyframe != KeyframeLandmarks::kUnknownKeyframe) {
        return in + "keyframe id is negative";
      }
      if (f > 0 && k.keyframe <= s.keyframes[f - 1].keyframe) {
        return in + "keyframe ids do not strictly increase";
      }
      for (size_t l = 1; l < k.landmark_ids.size(); ++l) {
        if (k.landmark_ids[l] <= k.landmark_ids[l - 1]) {
          return in + "landmark ids do not strictly increase";
        }
      }
    }
  }
  for (size_t i = 0; i < backoffs.size(); ++i) {
    const FusionPairBackoff& b = backoffs[i];
    const std::string at =
        "back-off of pair (" + std::to_string(b.older) + ", " + std::to_string(b.newer) + "): ";
    if (b.older >= b.newer) return at + "older is not below newer";
    if (i > 0 &&
        std::pair{b.older, b.newer} <= std::pair{backoffs[i - 1].older, backoffs[i - 1].newer}) {
      return at + "pairs do not strictly increase";
    }
    if (b.rejections < 0) return at + "negative rejection count";
    if (!std::isfinite(b.retry_in_s) || b.retry_in_s < 0.0) {
      return at + "retry_in_s is not finite and >= 0";
    }
  }
  return "";
}

}  // namespace cblox
