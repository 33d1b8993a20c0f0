#include "core/maintenance/fusion_scheduler.h"

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <sstream>
#include <stdexcept>

namespace cblox {
namespace {

// Adds `ids` (any order) to the ascending set `into`.
void mergeInto(std::vector<uint64_t>* into, std::span<const uint64_t> ids) {
  const size_t old_size = into->size();
  into->insert(into->end(), ids.begin(), ids.end());
  std::sort(into->begin() + static_cast<std::ptrdiff_t>(old_size), into->end());
  std::inplace_merge(into->begin(), into->begin() + static_cast<std::ptrdiff_t>(old_size),
                     into->end());
  into->erase(std::unique(into->begin(), into->end()), into->end());
}

// Adds one keyframe's landmarks to a subvolume's ascending keyframe list.
void addToKeyframes(std::vector<KeyframeLandmarks>* keyframes, int64_t keyframe,
                    std::span<const uint64_t> ids) {
  auto it =
      std::lower_bound(keyframes->begin(), keyframes->end(), keyframe,
                       [](const KeyframeLandmarks& k, int64_t id) { return k.keyframe < id; });
  if (it == keyframes->end() || it->keyframe != keyframe) {
    it = keyframes->insert(it, KeyframeLandmarks{keyframe, {}});
  }
  mergeInto(&it->landmark_ids, ids);
}

}  // namespace

const char* pairKeyframesName(PairKeyframes choice) {
  switch (choice) {
    case PairKeyframes::kAnchors:
      return "anchors";
    case PairKeyframes::kMostShared:
      return "most_shared";
    case PairKeyframes::kMostSharedOnRevisits:
      return "most_shared_on_revisits";
  }
  return "?";
}

bool parsePairKeyframes(const std::string& name, PairKeyframes* choice) {
  if (name == "anchors") {
    *choice = PairKeyframes::kAnchors;
  } else if (name == "most_shared") {
    *choice = PairKeyframes::kMostShared;
  } else if (name == "most_shared_on_revisits") {
    *choice = PairKeyframes::kMostSharedOnRevisits;
  } else {
    return false;
  }
  return true;
}

std::string FusionSchedulerConfig::validate() const {
  if (const std::string e = candidates.validate(); !e.empty()) return "candidates." + e;
  std::ostringstream error;
  if (!(q_min > 0.0) || !std::isfinite(q_min)) {
    error << "q_min must be finite and > 0, got " << q_min;
  } else if (pair_keyframes != PairKeyframes::kAnchors &&
             pair_keyframes != PairKeyframes::kMostShared &&
             pair_keyframes != PairKeyframes::kMostSharedOnRevisits) {
    error << "pair_keyframes is not a PairKeyframes value";
  } else if (revisit_keyframe_gap < 1) {
    error << "revisit_keyframe_gap must be >= 1, got " << revisit_keyframe_gap;
  } else if (max_pairs_per_request < 1) {
    error << "max_pairs_per_request must be >= 1, got " << max_pairs_per_request;
  } else if (!(reply_timeout_s > 0.0) || !std::isfinite(reply_timeout_s)) {
    error << "reply_timeout_s must be finite and > 0, got " << reply_timeout_s;
  } else if (!(retry_after_s >= 0.0) || !std::isfinite(retry_after_s)) {
    error << "retry_after_s must be finite and >= 0, got " << retry_after_s;
  } else if (!(max_retry_after_s >= retry_after_s) || !std::isfinite(max_retry_after_s)) {
    error << "max_retry_after_s must be finite and >= retry_after_s, got " << max_retry_after_s;
  }
  return error.str();
}

FusionScheduler::FusionScheduler(const FusionSchedulerConfig& config) : config_(config) {
  if (const std::string e = config_.validate(); !e.empty()) {
    throw std::invalid_argument("FusionSchedulerConfig: " + e);
  }
}

void FusionScheduler::addSubvolume(int64_t subvolume, int64_t anchor_keyframe) {
  anchors_[subvolume] = anchor_keyframe;
  keyframes_[subvolume];
  graph_.addSubvolume(subvolume);
}

bool FusionScheduler::addKeyframeLandmarks(int64_t subvolume, int64_t keyframe,
                                           std::span<const uint64_t> landmark_ids) {
  if (!anchors_.contains(subvolume)) return false;
  graph_.addLandmarks(subvolume, landmark_ids);
  addToKeyframes(&keyframes_[subvolume], keyframe, landmark_ids);
  return true;
}

bool FusionScheduler::addSubvolumeSharingAnchor(int64_t subvolume, int64_t home) {
  const auto home_anchor = anchors_.find(home);
  if (home_anchor == anchors_.end()) return false;
  const int64_t anchor = home_anchor->second;
  addSubvolume(subvolume, anchor);
  const std::vector<KeyframeLandmarks>& held = keyframes_.at(home);
  const auto it =
      std::lower_bound(held.begin(), held.end(), anchor,
                       [](const KeyframeLandmarks& k, int64_t id) { return k.keyframe < id; });
  if (it != held.end() && it->keyframe == anchor) {
    const std::vector<uint64_t> landmarks = it->landmark_ids;  // keyframes_ may rehash
    addKeyframeLandmarks(subvolume, anchor, landmarks);
  }
  return true;
}

void FusionScheduler::lockForFusion(const FusionPair& pair) {
  const PairKey key{pair.older, pair.newer};
  retry_at_.erase(key);
  rejections_.erase(key);
  fusing_.insert(pair.older);
  fusing_.insert(pair.newer);
  ++fusing_pairs_;
}

bool FusionScheduler::fusedWithoutCovariance(int64_t older, int64_t newer) const {
  const int64_t anchor = anchors_.at(newer);
  if (anchors_.at(older) == anchor) return true;
  const auto holder = absorbed_.find(anchor);
  return holder != absorbed_.end() && holder->second == older;
}

std::vector<FusionPair> FusionScheduler::takeSameAnchorPairs(int64_t active_subvolume) {
  std::vector<FusionPair> pairs;
  if (!config_.enabled) return pairs;
  const auto free = [&](int64_t subvolume) {
    return subvolume != active_subvolume && !fusing_.contains(subvolume) &&
           anchors_.contains(subvolume);
  };
  // anchor -> the free subvolumes anchored there, ascending
  absl::flat_hash_map<int64_t, std::vector<int64_t>> groups;
  for (const auto& [subvolume, anchor] : anchors_) {
    if (free(subvolume)) groups[anchor].push_back(subvolume);
  }
  absl::flat_hash_set<int64_t> used;
  const auto take = [&](int64_t older, int64_t newer, int64_t older_keyframe,
                        int64_t newer_keyframe) {
    FusionPair pair;
    pair.older = older;
    pair.newer = newer;
    pair.older_keyframe = older_keyframe;
    pair.newer_keyframe = newer_keyframe;
    pair.shared_landmarks = graph_.weight(older, newer);
    used.insert(older);
    used.insert(newer);
    pairs.push_back(pair);
  };
  std::vector<int64_t> anchors;
  for (auto& [anchor, group] : groups) {
    std::sort(group.begin(), group.end());
    anchors.push_back(anchor);
  }
  std::sort(anchors.begin(), anchors.end());  // a deterministic order of pairs
  for (const int64_t anchor : anchors) {
    const std::vector<int64_t>& group = groups.at(anchor);
    const int64_t first = group.front();
    if (used.contains(first)) continue;
    const auto holder = absorbed_.find(anchor);
    if (holder != absorbed_.end() && holder->second < first && free(holder->second) &&
        !used.contains(holder->second)) {
      take(holder->second, first, anchors_.at(holder->second), anchor);
    } else if (group.size() >= 2 && !used.contains(group[1])) {
      take(first, group[1], anchor, anchor);
    }
  }
  for (const FusionPair& pair : pairs) {
    lockForFusion(pair);
    ++stats_.same_anchor;
  }
  std::sort(pairs.begin(), pairs.end(), [](const FusionPair& x, const FusionPair& y) {
    return std::pair{x.older, x.newer} < std::pair{y.older, y.newer};
  });
  return pairs;
}

void FusionScheduler::removeSubvolume(int64_t subvolume) {
  absl::erase_if(absorbed_, [&](const auto& entry) { return entry.second == subvolume; });
  anchors_.erase(subvolume);
  keyframes_.erase(subvolume);
  graph_.removeSubvolume(subvolume);
}

std::tuple<int64_t, int64_t, int> FusionScheduler::mostSharedKeyframes(int64_t older,
                                                                       int64_t newer) const {
  const std::vector<KeyframeLandmarks>& a = keyframes_.at(older);
  const std::vector<KeyframeLandmarks>& b = keyframes_.at(newer);
  // landmark -> indices (ascending) of older's keyframes that observed it
  absl::flat_hash_map<uint64_t, std::vector<uint32_t>> observers;
  for (uint32_t i = 0; i < a.size(); ++i) {
    if (a[i].keyframe == KeyframeLandmarks::kUnknownKeyframe) continue;
    for (const uint64_t l : a[i].landmark_ids) observers[l].push_back(i);
  }
  std::tuple<int64_t, int64_t, int> best{anchors_.at(older), anchors_.at(newer), 0};
  std::vector<int> counts(a.size());
  for (const KeyframeLandmarks& k : b) {
    if (k.keyframe == KeyframeLandmarks::kUnknownKeyframe) continue;
    std::fill(counts.begin(), counts.end(), 0);
    for (const uint64_t l : k.landmark_ids) {
      const auto it = observers.find(l);
      if (it == observers.end()) continue;
      for (const uint32_t i : it->second) ++counts[i];
    }
    for (size_t i = 0; i < a.size(); ++i) {
      // Strictly more: ties keep the lower ids (both lists ascend).
      if (counts[i] > std::get<2>(best)) best = {a[i].keyframe, k.keyframe, counts[i]};
    }
  }
  return best;
}

std::optional<FusionCovarianceRequest> FusionScheduler::nextRequest(int64_t active_subvolume,
                                                                    double now_s) {
  if (in_flight_ && now_s - in_flight_->sent_s >= config_.reply_timeout_s) {
    ++stats_.requests_timed_out;
    timed_out_.push_back(std::move(in_flight_->request));
    if (timed_out_.size() > kKeptTimedOut) timed_out_.pop_front();
    in_flight_.reset();
  }
  if (!config_.enabled || in_flight_) return std::nullopt;

  FusionCovarianceRequest request;
  absl::flat_hash_set<int64_t> used;
  for (const CovisibilityCandidate& c : graph_.candidates(config_.candidates)) {
    if (static_cast<int>(request.pairs.size()) >= config_.max_pairs_per_request) break;
    const int64_t older = std::min(c.a, c.b), newer = std::max(c.a, c.b);
    if (older == active_subvolume || newer == active_subvolume) continue;
    if (fusing_.contains(older) || fusing_.contains(newer)) continue;
    if (used.contains(older) || used.contains(newer)) continue;
    if (fusedWithoutCovariance(older, newer)) continue;  // takeSameAnchorPairs' pairs
    const PairKey key{older, newer};
    if (const auto it = retry_at_.find(key); it != retry_at_.end() && now_s < it->second) {
      continue;
    }
    FusionPair pair;
    pair.older = older;
    pair.newer = newer;
    pair.older_keyframe = anchors_.at(older);
    pair.newer_keyframe = anchors_.at(newer);
    if (config_.pair_keyframes != PairKeyframes::kAnchors) {
      const auto [older_keyframe, newer_keyframe, shared] = mostSharedKeyframes(older, newer);
      if (config_.pair_keyframes == PairKeyframes::kMostShared ||
          std::abs(newer_keyframe - older_keyframe) >= config_.revisit_keyframe_gap) {
        pair.older_keyframe = older_keyframe;
        pair.newer_keyframe = newer_keyframe;
        pair.keyframe_shared_landmarks = shared;
      }
    }
    pair.shared_landmarks = c.shared;
    request.pairs.push_back(pair);
    used.insert(older);
    used.insert(newer);
    if (proposed_.insert(key).second) ++stats_.candidates;
  }
  if (request.pairs.empty()) return std::nullopt;
  request.request_id = next_request_id_++;
  stats_.requested += request.pairs.size();
  in_flight_ = InFlight{request, now_s};
  return request;
}

std::vector<FusionPair> FusionScheduler::onReply(int64_t request_id,
                                                 std::span<const FusionCovarianceAnswer> answers,
                                                 double now_s) {
  std::vector<FusionPair> accepted;
  std::vector<FusionPair> pairs;
  if (in_flight_ && in_flight_->request.request_id == request_id) {
    pairs = std::move(in_flight_->request.pairs);
    in_flight_.reset();
  } else {
    const auto late = std::find_if(timed_out_.begin(), timed_out_.end(),
                                   [&](const auto& r) { return r.request_id == request_id; });
    if (late == timed_out_.end()) {
      ++stats_.replies_ignored;
      return accepted;
    }
    ++stats_.late_replies;
    pairs = std::move(late->pairs);
    timed_out_.erase(late);
  }
  const bool sizes_match = answers.size() == pairs.size();
  for (size_t k = 0; k < pairs.size(); ++k) {
    const FusionPair& pair = pairs[k];
    const PairKey key{pair.older, pair.newer};
    if (!sizes_match || !answers[k].ok) {
      ++stats_.covariance_errors;
      retry_at_[key] = now_s + config_.retry_after_s;
      continue;
    }
    if (!(answers[k].q >= config_.q_min)) {
      ++stats_.rejected_by_q;
      const int times = ++rejections_[key];
      retry_at_[key] =
          now_s + std::min(config_.retry_after_s * std::ldexp(1.0, std::min(times - 1, 30)),
                           config_.max_retry_after_s);
      continue;
    }
    // Removed or taken by another fusion since the request: not fused, not a rejection.
    if (!anchors_.contains(pair.older) || !anchors_.contains(pair.newer) ||
        fusing_.contains(pair.older) || fusing_.contains(pair.newer)) {
      continue;
    }
    lockForFusion(pair);
    ++stats_.accepted;
    accepted.push_back(pair);
  }
  return accepted;
}

void FusionScheduler::onFused(const FusionPair& pair) {
  if (fusing_.erase(pair.older) + fusing_.erase(pair.newer) > 0 && fusing_pairs_ > 0) {
    --fusing_pairs_;
  }
  graph_.merge(pair.older, pair.newer);
  if (const auto it = anchors_.find(pair.newer);
      it != anchors_.end() && anchors_.contains(pair.older)) {
    // The newer's voxels, and those of anything fused into it before, are the older's now.
    for (auto& [anchor, holder] : absorbed_) {
      if (holder == pair.newer) holder = pair.older;
    }
    absorbed_[it->second] = pair.older;
  }
  anchors_.erase(pair.newer);
  if (const auto it = keyframes_.find(pair.newer); it != keyframes_.end()) {
    if (anchors_.contains(pair.older)) {
      std::vector<KeyframeLandmarks>& kept = keyframes_[pair.older];
      for (const KeyframeLandmarks& k : it->second) {
        addToKeyframes(&kept, k.keyframe, k.landmark_ids);
      }
    }
    keyframes_.erase(it);
  }
  ++stats_.fused;
}

void FusionScheduler::onFusionFailed(const FusionPair& pair, double now_s) {
  if (fusing_.erase(pair.older) + fusing_.erase(pair.newer) > 0 && fusing_pairs_ > 0) {
    --fusing_pairs_;
  }
  retry_at_[PairKey{pair.older, pair.newer}] = now_s + config_.retry_after_s;
  ++stats_.fusions_failed;
}

FusionSchedulerState FusionScheduler::exportState(double now_s) const {
  FusionSchedulerState state;
  for (const auto& [subvolume, keyframes] : keyframes_) {
    state.subvolumes.push_back(SubvolumeLandmarks{subvolume, keyframes});
  }
  std::sort(state.subvolumes.begin(), state.subvolumes.end(),
            [](const auto& x, const auto& y) { return x.subvolume < y.subvolume; });
  absl::flat_hash_set<PairKey> keys;
  for (const auto& [key, at] : retry_at_) keys.insert(key);
  for (const auto& [key, times] : rejections_) keys.insert(key);
  for (const PairKey& key : keys) {
    FusionPairBackoff b;
    b.older = key.first;
    b.newer = key.second;
    if (const auto it = rejections_.find(key); it != rejections_.end()) b.rejections = it->second;
    if (const auto it = retry_at_.find(key); it != retry_at_.end()) {
      b.retry_in_s = std::max(0.0, it->second - now_s);
    }
    if (b.rejections == 0 && b.retry_in_s == 0.0) continue;  // nothing left to remember
    state.backoffs.push_back(b);
  }
  std::sort(state.backoffs.begin(), state.backoffs.end(), [](const auto& x, const auto& y) {
    return std::pair{x.older, x.newer} < std::pair{y.older, y.newer};
  });
  return state;
}

size_t FusionScheduler::restoreState(const FusionSchedulerState& state, double now_s) {
  size_t ignored = 0;
  for (const SubvolumeLandmarks& s : state.subvolumes) {
    if (!anchors_.contains(s.subvolume)) {
      ++ignored;
      continue;
    }
    for (const KeyframeLandmarks& k : s.keyframes) {
      addKeyframeLandmarks(s.subvolume, k.keyframe, k.landmark_ids);
    }
  }
  for (const FusionPairBackoff& b : state.backoffs) {
    if (!anchors_.contains(b.older) || !anchors_.contains(b.newer)) {
      ++ignored;
      continue;
    }
    const PairKey key{b.older, b.newer};
    if (b.rejections > 0) rejections_[key] = b.rejections;
    if (b.retry_in_s > 0.0) retry_at_[key] = now_s + b.retry_in_s;
  }
  return ignored;
}

}  // namespace cblox
