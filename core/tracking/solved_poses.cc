#include "core/tracking/solved_poses.h"

#include <stdexcept>

namespace cblox {

void newKeyframesFollowTheirParent(const SparseMap& map, KeyframePoses* before) {
  for (Keyframe* k : map.keyframes()) {
    if (before->count(k) || k->parent() == nullptr || !before->count(k->parent())) continue;
    const Transformationd T_Ck_Cp = k->T_C_G() * before->at(k->parent()).inverse();
    (*before)[k] = k->T_C_G();
    k->setPose(T_Ck_Cp * k->parent()->T_C_G());
  }
}

void applySolvedPoses(SparseMap* map, std::span<Keyframe* const> keyframes,
                      std::span<const Transformationd> read_T_C_G,
                      std::span<const Transformationd> solved_T_C_G,
                      const std::map<LandmarkId, const Keyframe*>& anchor_of,
                      const ScalePyramid& pyramid) {
  if (read_T_C_G.size() != keyframes.size() || solved_T_C_G.size() != keyframes.size()) {
    throw std::invalid_argument("applySolvedPoses: one read and one solved pose per keyframe");
  }
  KeyframePoses before;  // the poses just before this
  for (size_t v = 0; v < keyframes.size(); ++v) {
    Keyframe* k = keyframes[v];
    before[k] = k->T_C_G();
    if (k->bad()) continue;
    const Transformationd since_read = k->T_C_G() * read_T_C_G[v].inverse();
    k->setPose(since_read * solved_T_C_G[v]);
  }
  newKeyframesFollowTheirParent(*map, &before);
  landmarksFollowTheirKeyframe(map, before, anchor_of, {}, pyramid);
}

void landmarksFollowTheirKeyframe(SparseMap* map, const KeyframePoses& before,
                                  const std::map<LandmarkId, const Keyframe*>& anchor_of,
                                  const std::set<const Landmark*>& skip,
                                  const ScalePyramid& pyramid) {
  for (Landmark* l : map->landmarks()) {
    if (skip.count(l)) continue;
    const auto anchor = anchor_of.find(l->id);
    const Keyframe* ref = anchor != anchor_of.end() ? anchor->second : l->referenceKeyframe();
    if (ref == nullptr || ref->bad()) continue;
    const auto was = before.find(ref);
    if (was == before.end()) continue;
    l->setPosition(ref->T_G_C() * (was->second * l->position()));
    l->updateNormalAndDepth(pyramid);
  }
}

}  // namespace cblox
