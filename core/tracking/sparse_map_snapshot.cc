#include "core/tracking/sparse_map_snapshot.h"

#include <cmath>
#include <set>
#include <sstream>

#include "core/tracking/keyframe.h"
#include "core/tracking/sparse_map.h"

namespace cblox {

namespace {

bool finitePose(const Transformationd& T) {
  return T.translation().allFinite() && T.rotation().coeffs().allFinite();
}

std::string keyframeProblem(const KeyframeSnapshot& k, size_t n, int pyramid_levels) {
  const auto known = [n](KeyframeId id) { return id >= 0 && static_cast<size_t>(id) < n; };
  if (!finitePose(k.T_C_G) || !finitePose(k.T_parent_this)) return "a non-finite pose";
  if (!k.features) return "no features";
  const FrameFeatures& f = *k.features;
  if (f.descriptors.size() != f.size() || f.right_u.size() != f.size() ||
      f.depth.size() != f.size()) {
    return "feature vectors of different lengths";
  }
  if (k.bad && f.size() != 0) return "features on a culled keyframe";
  for (const Keypoint& p : f.keypoints) {
    if (p.octave < 0 || p.octave >= pyramid_levels) {
      return "keypoint octave " + std::to_string(p.octave) + " outside [0, " +
             std::to_string(pyramid_levels) + ")";
    }
    if (!std::isfinite(p.u) || !std::isfinite(p.v) || !std::isfinite(p.angle_deg)) {
      return "a non-finite keypoint";
    }
  }
  if (k.parent != -1 && (!known(k.parent) || k.parent == k.id)) {
    return "parent " + std::to_string(k.parent) + " is not another keyframe";
  }
  KeyframeId previous = -1;
  for (const auto& [other, w] : k.connections) {
    if (!known(other) || other == k.id || other <= previous) {
      return "connection to " + std::to_string(other) +
             " is not another keyframe in ascending order";
    }
    if (w < 1) return "connection weight " + std::to_string(w) + " < 1";
    previous = other;
  }
  previous = -1;
  for (const KeyframeId other : k.loop_edges) {
    if (!known(other) || other == k.id || other <= previous) {
      return "loop edge to " + std::to_string(other) + " is not another keyframe in ascending order";
    }
    previous = other;
  }
  return {};
}

int weightIn(const KeyframeSnapshot& k, KeyframeId other) {
  for (const auto& [id, w] : k.connections) {
    if (id == other) return w;
  }
  return 0;
}

}  // namespace

std::string SparseMapSnapshot::validate(int pyramid_levels) const {
  const size_t n = keyframes.size();
  for (size_t i = 0; i < n; ++i) {
    const KeyframeSnapshot& k = keyframes[i];
    if (k.id != static_cast<KeyframeId>(i)) {
      return "keyframe " + std::to_string(i) + " has id " + std::to_string(k.id);
    }
    std::string problem = keyframeProblem(k, n, pyramid_levels);
    if (!problem.empty()) return "keyframe " + std::to_string(i) + ": " + problem;
    for (const auto& [other, w] : k.connections) {
      if (weightIn(keyframes[static_cast<size_t>(other)], k.id) != w) {
        return "keyframe " + std::to_string(i) + ": connection to " + std::to_string(other) +
               " (weight " + std::to_string(w) + ") is not listed the same way there";
      }
    }
  }
  std::set<std::pair<KeyframeId, uint32_t>> observed;
  LandmarkId previous = 0;
  for (size_t j = 0; j < landmarks.size(); ++j) {
    const LandmarkSnapshot& l = landmarks[j];
    const std::string name = "landmark " + std::to_string(l.id);
    if (l.id >= next_landmark_id || (j > 0 && l.id <= previous)) {
      return name + ": id not ascending or not below the next landmark id " +
             std::to_string(next_landmark_id);
    }
    previous = l.id;
    if (!l.p_G.allFinite() || !l.normal.allFinite() || !std::isfinite(l.min_distance) ||
        !std::isfinite(l.max_distance)) {
      return name + ": non-finite position, normal or distance";
    }
    if (l.reference != -1 && (l.reference < 0 || static_cast<size_t>(l.reference) >= n)) {
      return name + ": reference " + std::to_string(l.reference) + " is not a keyframe";
    }
    KeyframeId previous_keyframe = -1;
    for (const auto& [keyframe, index] : l.observations) {
      if (keyframe <= previous_keyframe || static_cast<size_t>(keyframe) >= n) {
        return name + ": observation by " + std::to_string(keyframe) +
               " is not a keyframe in ascending order";
      }
      previous_keyframe = keyframe;
      const KeyframeSnapshot& k = keyframes[static_cast<size_t>(keyframe)];
      if (k.bad) return name + ": observed by culled keyframe " + std::to_string(keyframe);
      if (index >= k.features->size()) {
        return name + ": feature " + std::to_string(index) + " of keyframe " +
               std::to_string(keyframe) + " out of range";
      }
      if (!observed.emplace(keyframe, index).second) {
        return name + ": feature " + std::to_string(index) + " of keyframe " +
               std::to_string(keyframe) + " already observes another landmark";
      }
    }
  }
  return {};
}

const std::shared_ptr<const FrameFeatures>& emptyFrameFeatures() {
  static const auto kNone = std::make_shared<const FrameFeatures>();
  return kNone;
}

SparseMapSnapshot takeSparseMapSnapshot(const SparseMap& map) {
  SparseMapSnapshot s;
  s.next_landmark_id = map.nextLandmarkId();
  s.change_index = map.changeIndex();
  s.keyframes.reserve(map.allKeyframes().size());
  for (const auto& k : map.allKeyframes()) {
    KeyframeSnapshot ks;
    ks.id = k->id;
    ks.frame_id = k->frame_id;
    ks.timestamp_ns = k->timestamp_ns;
    ks.T_C_G = k->T_C_G();
    ks.bad = k->bad();
    ks.first_connection_pending = k->firstConnectionPending();
    ks.parent = k->parent() != nullptr ? k->parent()->id : -1;
    ks.T_parent_this = k->T_parent_this();
    for (const auto& [other, w] : k->connections()) ks.connections.emplace_back(other->id, w);
    for (const Keyframe* other : k->loopEdges()) ks.loop_edges.push_back(other->id);
    ks.features = k->bad() ? emptyFrameFeatures() : k->sharedFeatures();
    s.keyframes.push_back(std::move(ks));
  }
  const std::vector<Landmark*> landmarks = map.landmarks();
  s.landmarks.reserve(landmarks.size());
  for (const Landmark* l : landmarks) {
    LandmarkSnapshot ls;
    ls.id = l->id;
    ls.p_G = l->position();
    ls.normal = l->normal();
    ls.min_distance = l->rawMinDistance();
    ls.max_distance = l->rawMaxDistance();
    ls.descriptor = l->descriptor();
    ls.reference = l->referenceKeyframe() != nullptr ? l->referenceKeyframe()->id : -1;
    ls.first_keyframe_id = l->first_keyframe_id;
    ls.visible = l->visible();
    ls.found = l->found();
    for (const auto& [keyframe, index] : l->observations()) {
      ls.observations.emplace_back(keyframe->id, index);
    }
    s.landmarks.push_back(std::move(ls));
  }
  return s;
}

}  // namespace cblox
