#include "core/tracking/sparse_map.h"

#include <algorithm>
#include <stdexcept>
#include <utility>

namespace cblox {

Keyframe* SparseMap::addKeyframe(uint64_t frame_id, int64_t timestamp_ns,
                                 std::shared_ptr<const FrameFeatures> features,
                                 const Transformationd& T_C_G) {
  keyframes_.push_back(std::make_unique<Keyframe>(static_cast<KeyframeId>(keyframes_.size()),
                                                  frame_id, timestamp_ns, std::move(features),
                                                  T_C_G));
  ++num_good_keyframes_;
  return keyframes_.back().get();
}

std::shared_ptr<Landmark> SparseMap::addLandmark(const Eigen::Vector3d& p_G, Keyframe* reference) {
  auto landmark = std::make_shared<Landmark>(next_landmark_id_++, p_G, reference);
  landmark->first_keyframe_id = reference != nullptr ? reference->id : 0;
  landmarks_.emplace(landmark->id, landmark);
  return landmark;
}

void SparseMap::addObservation(Keyframe* keyframe, uint32_t index, Landmark* landmark) {
  keyframe->setLandmark(index, landmark);
  landmark->addObservation(keyframe, index, keyframe->features().hasDepth(index));
}

void SparseMap::eraseObservation(Keyframe* keyframe, uint32_t index) {
  Landmark* landmark = keyframe->landmark(index);
  if (landmark == nullptr) return;
  keyframe->setLandmark(index, nullptr);
  landmark->eraseObservation(keyframe, keyframe->features().hasDepth(index));
}

void SparseMap::retireLandmark(Landmark* landmark) {
  if (landmark == nullptr || landmark->bad()) return;
  landmark->setBad();
  const auto observations = landmark->observations();  // copy: erased below
  for (const auto& [keyframe, index] : observations) {
    if (keyframe->landmark(index) == landmark) keyframe->setLandmark(index, nullptr);
    landmark->eraseObservation(keyframe, keyframe->features().hasDepth(index));
  }
  landmarks_.erase(landmark->id);  // may free it, unless a frame still holds it
}

void SparseMap::replaceLandmark(Landmark* landmark, Landmark* by) {
  if (landmark == nullptr || by == nullptr || landmark == by || landmark->bad()) return;
  const auto it = landmarks_.find(by->id);
  if (it == landmarks_.end()) return;  // `by` is not (or no longer) in the map
  std::shared_ptr<Landmark> by_shared = it->second;
  const auto observations = landmark->observations();
  for (const auto& [keyframe, index] : observations) {
    landmark->eraseObservation(keyframe, keyframe->features().hasDepth(index));
    if (by->indexIn(keyframe) < 0) {
      keyframe->setLandmark(index, by);
      by->addObservation(keyframe, index, keyframe->features().hasDepth(index));
    } else {
      keyframe->setLandmark(index, nullptr);
    }
  }
  by->increaseVisible(landmark->visible());
  by->increaseFound(landmark->found());
  by->updateDescriptor();
  landmark->setBad();
  landmark->setReplacement(std::move(by_shared));
  landmarks_.erase(landmark->id);
}

void SparseMap::cullKeyframe(Keyframe* keyframe) {
  if (keyframe == nullptr || keyframe->bad()) return;
  const std::vector<Landmark*> orphans = keyframe->cull();
  if (!keyframe->bad()) return;  // first keyframe or a loop keyframe: kept
  --num_good_keyframes_;
  for (Landmark* l : orphans) retireLandmark(l);
}

std::optional<KeyframeAncestor> SparseMap::goodAncestor(
    const Keyframe* keyframe, const std::function<bool(const Keyframe&)>& stop) {
  KeyframeAncestor result;
  const Keyframe* k = keyframe;
  // A culled keyframe's parent never changes (it is no child of anyone), and ids grow
  // towards the leaves, so the chain is finite; the bound only guards a corrupt graph.
  for (size_t steps = 0; k != nullptr && k->bad() && !(stop && stop(*k)); ++steps) {
    if (steps > (size_t{1} << 24)) return std::nullopt;
    result.T_A_K = k->T_parent_this() * result.T_A_K;
    k = k->parent();
  }
  if (k == nullptr) return std::nullopt;
  result.ancestor = k;
  return result;
}

void SparseMap::moveCulledKeyframes(KeyframePoseBatch* batch) {
  absl::flat_hash_map<KeyframeId, Transformationd> moved;
  moved.reserve(batch->size());
  for (const auto& [id, T_G_C] : *batch) moved.emplace(id, T_G_C);
  for (const std::unique_ptr<Keyframe>& k : keyframes_) {
    if (!k->bad() || moved.count(k->id)) continue;
    const std::optional<KeyframeAncestor> a = goodAncestor(k.get());
    if (!a) continue;
    const auto it = moved.find(a->ancestor->id);
    if (it == moved.end()) continue;
    const Transformationd T_G_K = it->second * a->T_A_K;
    k->setPose(T_G_K.inverse());
    batch->emplace_back(k->id, T_G_K);
  }
}

Keyframe* SparseMap::keyframe(KeyframeId id) const {
  return id >= 0 && static_cast<size_t>(id) < keyframes_.size()
             ? keyframes_[static_cast<size_t>(id)].get()
             : nullptr;
}

std::shared_ptr<Landmark> SparseMap::landmark(LandmarkId id) const {
  const auto it = landmarks_.find(id);
  return it == landmarks_.end() ? nullptr : it->second;
}

std::vector<Keyframe*> SparseMap::keyframes() const {
  std::vector<Keyframe*> result;
  result.reserve(num_good_keyframes_);
  for (const auto& k : keyframes_) {
    if (!k->bad()) result.push_back(k.get());
  }
  return result;
}

std::vector<Landmark*> SparseMap::landmarks() const {
  std::vector<Landmark*> result;
  result.reserve(landmarks_.size());
  for (const auto& [id, l] : landmarks_) result.push_back(l.get());
  std::sort(result.begin(), result.end(),
            [](const Landmark* a, const Landmark* b) { return a->id < b->id; });
  return result;
}

void SparseMap::restore(const SparseMapSnapshot& snapshot, int pyramid_levels,
                        KeyframeId next_keyframe_id, LandmarkId next_landmark_id) {
  if (!keyframes_.empty() || !landmarks_.empty()) {
    throw std::invalid_argument("cannot restore a snapshot into a map that is not empty");
  }
  const std::string problem = snapshot.validate(pyramid_levels);
  if (!problem.empty()) throw std::invalid_argument("inconsistent sparse map: " + problem);
  if (next_keyframe_id > static_cast<KeyframeId>(snapshot.keyframes.size()) + kMaxSkippedKeyframeIds) {
    throw std::invalid_argument("keyframe id floor " + std::to_string(next_keyframe_id) +
                                " is more than " + std::to_string(kMaxSkippedKeyframeIds) +
                                " above the map's " + std::to_string(snapshot.keyframes.size()) +
                                " keyframes");
  }

  for (const KeyframeSnapshot& k : snapshot.keyframes) {
    keyframes_.push_back(
        std::make_unique<Keyframe>(k.id, k.frame_id, k.timestamp_ns, k.features, k.T_C_G));
  }
  while (static_cast<KeyframeId>(keyframes_.size()) < next_keyframe_id) {
    const auto id = static_cast<KeyframeId>(keyframes_.size());
    keyframes_.push_back(
        std::make_unique<Keyframe>(id, 0, 0, emptyFrameFeatures(), Transformationd::Identity()));
    keyframes_.back()->restoreGraph({}, nullptr, {}, false, true, Transformationd::Identity());
  }
  num_good_keyframes_ = 0;
  for (const KeyframeSnapshot& k : snapshot.keyframes) {
    std::vector<std::pair<Keyframe*, int>> connections;
    connections.reserve(k.connections.size());
    for (const auto& [other, w] : k.connections) connections.emplace_back(keyframe(other), w);
    std::vector<Keyframe*> loop_edges;
    for (const KeyframeId other : k.loop_edges) loop_edges.push_back(keyframe(other));
    keyframes_[static_cast<size_t>(k.id)]->restoreGraph(
        connections, keyframe(k.parent), loop_edges, k.first_connection_pending, k.bad,
        k.T_parent_this);
    if (!k.bad) ++num_good_keyframes_;
  }
  for (const LandmarkSnapshot& l : snapshot.landmarks) {
    auto landmark = std::make_shared<Landmark>(l.id, l.p_G, keyframe(l.reference));
    landmark->first_keyframe_id = l.first_keyframe_id;
    for (const auto& [keyframe_id, index] : l.observations) {
      addObservation(keyframe(keyframe_id), index, landmark.get());
    }
    landmark->restoreDerived(l.descriptor, l.normal, l.min_distance, l.max_distance, l.visible,
                             l.found);
    landmarks_.emplace(l.id, std::move(landmark));
  }
  next_landmark_id_ = std::max(snapshot.next_landmark_id, next_landmark_id);
  change_index_ = snapshot.change_index;
}

}  // namespace cblox
