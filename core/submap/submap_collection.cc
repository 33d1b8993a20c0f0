#include "core/submap/submap_collection.h"

#include <algorithm>
#include <stdexcept>
#include <string>
#include <utility>

namespace cblox {

std::string SubmapCollectionConfig::validate() const {
  const std::string error = layer.validate();
  return error.empty() ? error : "layer." + error;
}

SubmapCollection::SubmapCollection(const SubmapCollectionConfig& config) : config_(config) {
  const std::string error = config_.validate();
  if (!error.empty()) throw std::invalid_argument("SubmapCollectionConfig: " + error);
}

void SubmapCollection::finishOutsideLock(const std::shared_ptr<Submap>& previous) {
  if (previous) previous->finish();
}

std::shared_ptr<Submap> SubmapCollection::createSubmap(const Transformationd& T_G_M,
                                                       KeyframeId anchor_keyframe,
                                                       int64_t creation_time_ns) {
  if (!isFinitePose(T_G_M)) {
    throw std::invalid_argument("SubmapCollection::createSubmap: T_G_M is not finite");
  }
  std::shared_ptr<Submap> previous;
  std::shared_ptr<Submap> submap;
  {
    std::lock_guard lock(mutex_);
    submap =
        std::make_shared<Submap>(next_id_, config_.layer, T_G_M, anchor_keyframe, creation_time_ns);
    ++next_id_;
    submaps_.emplace(submap->id(), submap);
    anchored_[anchor_keyframe].push_back(submap->id());
    previous = std::move(active_);
    active_ = submap;
  }
  finishOutsideLock(previous);
  return submap;
}

std::shared_ptr<Submap> SubmapCollection::restoreSubmap(SubmapId id, TsdfLayer layer,
                                                        const Transformationd& T_G_M,
                                                        KeyframeId anchor_keyframe,
                                                        int64_t creation_time_ns, bool finished) {
  if (!isFinitePose(T_G_M)) {
    throw std::invalid_argument("SubmapCollection::restoreSubmap: T_G_M is not finite");
  }
  if (layer.voxelSize() != config_.layer.voxel_size ||
      layer.voxelsPerSide() != config_.layer.voxels_per_side) {
    throw std::invalid_argument(
        "SubmapCollection::restoreSubmap: the layer's config differs from the collection's");
  }
  // Built (and finished) before it becomes visible: nobody else can hold its layer lock.
  auto submap =
      std::make_shared<Submap>(id, std::move(layer), T_G_M, anchor_keyframe, creation_time_ns);
  if (finished) submap->finish();
  std::shared_ptr<Submap> previous;
  {
    std::lock_guard lock(mutex_);
    if (id < next_id_) {
      throw std::invalid_argument("SubmapCollection::restoreSubmap: id " + std::to_string(id) +
                                  " is below the next id " + std::to_string(next_id_));
    }
    next_id_ = id + 1;
    submaps_.emplace(id, submap);
    anchored_[anchor_keyframe].push_back(id);
    if (!finished) {
      previous = std::move(active_);
      active_ = submap;
    }
  }
  finishOutsideLock(previous);
  return submap;
}

SubmapId SubmapCollection::nextSubmapId() const {
  std::lock_guard lock(mutex_);
  return next_id_;
}

void SubmapCollection::reserveSubmapIds(SubmapId next_id) {
  std::lock_guard lock(mutex_);
  next_id_ = std::max(next_id_, next_id);
}

std::shared_ptr<Submap> SubmapCollection::getSubmap(SubmapId id) const {
  std::lock_guard lock(mutex_);
  const auto it = submaps_.find(id);
  return it == submaps_.end() ? nullptr : it->second;
}

std::shared_ptr<Submap> SubmapCollection::activeSubmap() const {
  std::lock_guard lock(mutex_);
  return active_;
}

void SubmapCollection::finishActiveSubmap() {
  std::shared_ptr<Submap> previous;
  {
    std::lock_guard lock(mutex_);
    previous = std::move(active_);
    active_.reset();
  }
  finishOutsideLock(previous);
}

bool SubmapCollection::removeSubmap(SubmapId id) {
  std::shared_ptr<Submap> removed;
  {
    std::lock_guard lock(mutex_);
    const auto it = submaps_.find(id);
    if (it == submaps_.end()) return false;
    removed = std::move(it->second);
    submaps_.erase(it);
    const auto anchor_it = anchored_.find(removed->anchorKeyframe());
    if (anchor_it != anchored_.end()) {
      std::erase(anchor_it->second, id);
      if (anchor_it->second.empty()) anchored_.erase(anchor_it);
    }
    if (active_ == removed) active_.reset();
  }
  // Finishing a removed active submap stops its integrator; a no-op for finished ones.
  finishOutsideLock(removed);
  return true;
}

std::vector<SubmapId> SubmapCollection::submapIds() const {
  std::lock_guard lock(mutex_);
  std::vector<SubmapId> ids;
  ids.reserve(submaps_.size());
  for (const auto& [id, submap] : submaps_) ids.push_back(id);
  return ids;
}

std::vector<std::shared_ptr<Submap>> SubmapCollection::submaps() const {
  std::lock_guard lock(mutex_);
  std::vector<std::shared_ptr<Submap>> result;
  result.reserve(submaps_.size());
  for (const auto& [id, submap] : submaps_) result.push_back(submap);
  return result;
}

SubmapCollectionState SubmapCollection::snapshot() const {
  std::lock_guard lock(mutex_);
  SubmapCollectionState state;
  state.submaps.reserve(submaps_.size());
  for (const auto& [id, submap] : submaps_) state.submaps.push_back(submap);
  state.active = active_;
  state.next_submap_id = next_id_;
  return state;
}

size_t SubmapCollection::size() const {
  std::lock_guard lock(mutex_);
  return submaps_.size();
}

KeyframePoseUpdateResult SubmapCollection::updateKeyframePoses(
    const std::vector<std::pair<KeyframeId, Transformationd>>& T_G_K) {
  KeyframePoseUpdateResult result;
  std::lock_guard lock(mutex_);
  for (const auto& [keyframe, pose] : T_G_K) {
    if (!isFinitePose(pose)) {
      ++result.poses_invalid;
      continue;
    }
    const auto anchor_it = anchored_.find(keyframe);
    bool known = anchor_it != anchored_.end();
    if (known) {
      for (const SubmapId id : anchor_it->second) {
        submaps_.at(id)->setT_G_M(pose);
        ++result.submaps_moved;
      }
    } else {
      for (const auto& [id, submap] : submaps_) {
        if (submap->hasKeyframe(keyframe)) {
          known = true;
          break;
        }
      }
    }
    ++(known ? result.keyframes_known : result.keyframes_unknown);
  }
  return result;
}

size_t SubmapCollection::numBlocks() const {
  std::lock_guard lock(mutex_);
  size_t blocks = 0;
  for (const auto& [id, submap] : submaps_) blocks += submap->numBlocks();
  return blocks;
}

size_t SubmapCollection::memoryBytes() const {
  std::lock_guard lock(mutex_);
  size_t bytes = 0;
  for (const auto& [id, submap] : submaps_) bytes += submap->memoryBytes();
  return bytes;
}

std::vector<SubmapPose> SubmapCollection::poseSnapshot() const {
  std::lock_guard lock(mutex_);
  std::vector<SubmapPose> poses;
  poses.reserve(submaps_.size());
  for (const auto& [id, submap] : submaps_) {
    poses.push_back(SubmapPose{id, submap->anchorKeyframe(), submap->T_G_M(), submap == active_});
  }
  return poses;
}

std::optional<SubmapPose> SubmapCollection::oldestSubmapWithKeyframe(KeyframeId keyframe) const {
  std::lock_guard lock(mutex_);
  for (const auto& [id, submap] : submaps_) {  // ascending ids
    if (submap->hasKeyframe(keyframe)) {
      return SubmapPose{id, submap->anchorKeyframe(), submap->T_G_M(), submap == active_};
    }
  }
  return std::nullopt;
}

}  // namespace cblox
