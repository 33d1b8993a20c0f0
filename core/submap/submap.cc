#include "core/submap/submap.h"

#include <algorithm>
#include <stdexcept>
#include <utility>

namespace cblox {

bool isFinitePose(const Transformationd& T) {
  return T.rotation().coeffs().allFinite() && T.translation().allFinite();
}

Submap::WriteLock& Submap::WriteLock::operator=(WriteLock&& other) noexcept {
  if (this != &other) {
    unlock();
    submap_ = other.submap_;
    lock_ = std::move(other.lock_);
  }
  return *this;
}

Submap::WriteLock::~WriteLock() { unlock(); }

void Submap::WriteLock::unlock() {
  if (!lock_.owns_lock()) return;
  submap_->refreshStatistics();
  // Bumped while the lock is still held: a reader that copies the layer under lockLayer()
  // after reading revision() sees either this frame's voxels or a newer revision.
  submap_->revision_.fetch_add(1, std::memory_order_acq_rel);
  lock_.unlock();
}

Submap::Submap(SubmapId id, const LayerConfig& layer_config, const Transformationd& T_G_M,
               KeyframeId anchor_keyframe, int64_t creation_time_ns)
    : id_(id),
      layer_config_(layer_config),
      anchor_keyframe_(anchor_keyframe),
      creation_time_ns_(creation_time_ns),
      T_G_M_(T_G_M),
      layer_(layer_config) {
  if (!isFinitePose(T_G_M)) throw std::invalid_argument("Submap: T_G_M is not finite");
  keyframe_ids_.insert(anchor_keyframe);
  refreshStatistics();
}

Submap::Submap(SubmapId id, TsdfLayer layer, const Transformationd& T_G_M,
               KeyframeId anchor_keyframe, int64_t creation_time_ns)
    : id_(id),
      layer_config_(layer.config()),
      anchor_keyframe_(anchor_keyframe),
      creation_time_ns_(creation_time_ns),
      T_G_M_(T_G_M),
      layer_(std::move(layer)) {
  if (!isFinitePose(T_G_M)) throw std::invalid_argument("Submap: T_G_M is not finite");
  keyframe_ids_.insert(anchor_keyframe);
  refreshStatistics();
  revision_.store(1, std::memory_order_release);  // restored: not the empty layer of revision 0
}

Transformationd Submap::T_G_M() const {
  std::lock_guard lock(meta_mutex_);
  return T_G_M_;
}

bool Submap::setT_G_M(const Transformationd& T_G_M) {
  if (!isFinitePose(T_G_M)) return false;
  std::lock_guard lock(meta_mutex_);
  T_G_M_ = T_G_M;
  return true;
}

Transformation Submap::T_M_C(const Transformationd& T_G_C) const {
  return (T_G_M().inverse() * T_G_C).cast<float>();
}

bool Submap::addKeyframe(KeyframeId id) {
  std::lock_guard lock(meta_mutex_);
  return keyframe_ids_.insert(id).second;
}

bool Submap::hasKeyframe(KeyframeId id) const {
  std::lock_guard lock(meta_mutex_);
  return keyframe_ids_.contains(id);
}

size_t Submap::numKeyframes() const {
  std::lock_guard lock(meta_mutex_);
  return keyframe_ids_.size();
}

std::vector<KeyframeId> Submap::keyframeIds() const {
  std::vector<KeyframeId> ids;
  {
    std::lock_guard lock(meta_mutex_);
    ids.assign(keyframe_ids_.begin(), keyframe_ids_.end());
  }
  std::sort(ids.begin(), ids.end());
  return ids;
}

void Submap::finish() {
  std::lock_guard lock(layer_mutex_);
  if (finished_.load(std::memory_order_relaxed)) return;
  refreshStatistics();
  finished_.store(true, std::memory_order_release);
}

Submap::WriteLock Submap::lockForIntegration() {
  std::unique_lock lock(layer_mutex_);
  if (finished_.load(std::memory_order_acquire)) return WriteLock();
  return WriteLock(this, std::move(lock));
}

void Submap::refreshStatistics() {
  num_blocks_.store(layer_.numBlocks(), std::memory_order_relaxed);
  memory_bytes_.store(layer_.memoryBytes(), std::memory_order_relaxed);
}

}  // namespace cblox
