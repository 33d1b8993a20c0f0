#include "core/tracking/keyframe.h"

#include <algorithm>
#include <atomic>
#include <utility>

#include "core/tracking/landmark.h"

namespace cblox {

bool KeyframeIdLess::operator()(const Keyframe* a, const Keyframe* b) const {
  return a->id < b->id;
}

namespace {
constexpr int kConnectionMinWeight = 15;  // ORB-SLAM2's UpdateConnections threshold
}  // namespace

Keyframe::Keyframe(KeyframeId id_, uint64_t frame_id_, int64_t timestamp_ns_,
                   std::shared_ptr<const FrameFeatures> features, const Transformationd& T_C_G)
    : id(id_),
      frame_id(frame_id_),
      timestamp_ns(timestamp_ns_),
      features_(std::move(features)),
      landmarks_(features_->size(), nullptr) {
  setPose(T_C_G);
}

int Keyframe::numTrackedLandmarks(int min_observations) const {
  int n = 0;
  for (const Landmark* l : landmarks_) {
    if (l == nullptr || l->bad()) continue;
    if (min_observations > 0 && l->numObservations() < min_observations) {
      continue;
    }
    ++n;
  }
  return n;
}

void Keyframe::updateConnections() {
  // Shared landmarks per other keyframe, counted in the other keyframes themselves (a fresh
  // stamp per call; callers hold the map's exclusive lock), then visited in id order.
  static std::atomic<uint64_t> last_stamp{0};
  const uint64_t stamp = ++last_stamp;
  std::vector<Keyframe*> others;
  for (const Landmark* l : landmarks_) {
    if (l == nullptr || l->bad()) continue;
    for (const auto& [other, index] : l->observations()) {
      if (other == this || other->bad()) continue;
      if (other->connection_count_stamp_ != stamp) {
        other->connection_count_stamp_ = stamp;
        other->connection_count_ = 0;
        others.push_back(other);
      }
      ++other->connection_count_;
    }
  }
  if (others.empty()) return;
  std::sort(others.begin(), others.end(), KeyframeIdLess{});
  Keyframe* best = nullptr;
  int best_weight = 0;
  for (Keyframe* other : others) {
    if (other->connection_count_ > best_weight) {
      best_weight = other->connection_count_;
      best = other;
    }
  }
  const auto keep = [&](Keyframe* other) {
    return other->connection_count_stamp_ == stamp &&
           (other->connection_count_ >= kConnectionMinWeight || other == best);
  };
  // Forget edges that no longer exist (both ends).
  for (auto it = connections_.begin(); it != connections_.end();) {
    if (!keep(it->first)) {
      it->first->eraseConnection(this);
      it = connections_.erase(it);
    } else {
      ++it;
    }
  }
  for (Keyframe* other : others) {
    if (!keep(other)) continue;
    connections_[other] = other->connection_count_;
    other->addConnection(this, other->connection_count_);
  }
  rebuildOrder();
  if (first_connection_ && id != 0) {
    first_connection_ = false;
    changeParent(best);
  }
}

void Keyframe::addConnection(Keyframe* other, int w) {
  const auto [it, inserted] = connections_.try_emplace(other, w);
  if (!inserted) {
    if (it->second == w) return;  // the order stays as it is
    it->second = w;
    removeFromOrder(other);
  }
  // The place rebuildOrder() would give it: after the heavier edges and the equal ones of
  // smaller id.
  size_t i = 0;
  while (i < ordered_neighbours_.size() &&
         (ordered_weights_[i] > w ||
          (ordered_weights_[i] == w && KeyframeIdLess{}(ordered_neighbours_[i], other)))) {
    ++i;
  }
  ordered_neighbours_.insert(ordered_neighbours_.begin() + static_cast<long>(i), other);
  ordered_weights_.insert(ordered_weights_.begin() + static_cast<long>(i), w);
}

void Keyframe::eraseConnection(Keyframe* other) {
  if (connections_.erase(other) > 0) removeFromOrder(other);
}

void Keyframe::removeFromOrder(Keyframe* other) {
  const auto it = std::find(ordered_neighbours_.begin(), ordered_neighbours_.end(), other);
  if (it == ordered_neighbours_.end()) return;
  ordered_weights_.erase(ordered_weights_.begin() + (it - ordered_neighbours_.begin()));
  ordered_neighbours_.erase(it);
}

void Keyframe::rebuildOrder() {
  std::vector<std::pair<int, Keyframe*>> pairs;
  pairs.reserve(connections_.size());
  for (const auto& [other, w] : connections_) pairs.emplace_back(w, other);
  // Decreasing weight; ties by increasing id (deterministic).
  std::stable_sort(pairs.begin(), pairs.end(),
                   [](const auto& a, const auto& b) { return a.first > b.first; });
  ordered_neighbours_.clear();
  ordered_weights_.clear();
  for (const auto& [w, other] : pairs) {
    ordered_neighbours_.push_back(other);
    ordered_weights_.push_back(w);
  }
}

std::vector<Keyframe*> Keyframe::bestCovisible(size_t n) const {
  const size_t count = std::min(n, ordered_neighbours_.size());
  return {ordered_neighbours_.begin(), ordered_neighbours_.begin() + static_cast<long>(count)};
}

std::vector<Keyframe*> Keyframe::covisibleWithWeightAtLeast(int w) const {
  std::vector<Keyframe*> result;
  for (size_t i = 0; i < ordered_neighbours_.size() && ordered_weights_[i] >= w; ++i) {
    result.push_back(ordered_neighbours_[i]);
  }
  return result;
}

int Keyframe::weight(const Keyframe* other) const {
  const auto it = connections_.find(const_cast<Keyframe*>(other));
  return it == connections_.end() ? 0 : it->second;
}

void Keyframe::changeParent(Keyframe* parent) {
  if (parent_ != nullptr) parent_->children_.erase(this);
  parent_ = parent;
  if (parent_ != nullptr) parent_->children_.insert(this);
}

std::vector<Landmark*> Keyframe::cull() {
  std::vector<Landmark*> orphans;
  if (bad_ || id == 0 || !loop_edges_.empty()) return orphans;
  for (auto& [other, w] : connections_) other->eraseConnection(this);
  for (size_t i = 0; i < landmarks_.size(); ++i) {
    Landmark* l = landmarks_[i];
    if (l == nullptr) continue;
    if (l->eraseObservation(this, features_->hasDepth(i))) orphans.push_back(l);
    landmarks_[i] = nullptr;
  }
  connections_.clear();
  ordered_neighbours_.clear();
  ordered_weights_.clear();

  // Re-parent the children (ORB-SLAM2): repeatedly attach the child with the strongest
  // covisibility edge to a keyframe already in the tree (the parent candidates).
  std::set<Keyframe*, KeyframeIdLess> candidates;
  if (parent_ != nullptr) candidates.insert(parent_);
  while (!children_.empty()) {
    Keyframe* best_child = nullptr;
    Keyframe* best_parent = nullptr;
    int best_weight = -1;
    for (Keyframe* child : children_) {
      if (child->bad()) continue;
      for (Keyframe* neighbour : child->covisibleByWeight()) {
        if (candidates.count(neighbour) == 0) continue;
        const int w = child->weight(neighbour);
        if (w > best_weight) {
          best_weight = w;
          best_child = child;
          best_parent = neighbour;
        }
      }
    }
    if (best_child == nullptr) break;
    best_child->changeParent(best_parent);
    candidates.insert(best_child);
    children_.erase(best_child);
  }
  // Children without a covisible candidate go to this keyframe's parent.
  const std::set<Keyframe*, KeyframeIdLess> rest = children_;
  for (Keyframe* child : rest) child->changeParent(parent_);
  if (parent_ != nullptr) {
    parent_->children_.erase(this);
    T_parent_this_ = parent_->T_C_G() * T_G_C_;
  }
  bad_ = true;
  return orphans;
}

void Keyframe::restoreGraph(const std::vector<std::pair<Keyframe*, int>>& connections,
                            Keyframe* parent, const std::vector<Keyframe*>& loop_edges,
                            bool first_connection_pending, bool bad,
                            const Transformationd& T_parent_this) {
  connections_.clear();
  for (const auto& [other, w] : connections) connections_[other] = w;
  rebuildOrder();
  if (bad) {
    parent_ = parent;  // a culled keyframe is no child of its parent (cull)
  } else {
    changeParent(parent);
  }
  loop_edges_ = {loop_edges.begin(), loop_edges.end()};
  first_connection_ = first_connection_pending;
  bad_ = bad;
  T_parent_this_ = T_parent_this;
}

}  // namespace cblox
