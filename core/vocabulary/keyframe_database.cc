#include "core/vocabulary/keyframe_database.h"

#include <algorithm>
#include <mutex>
#include <stdexcept>

#include <absl/container/flat_hash_set.h>

namespace cblox {
namespace {

/// Shared-word count and partial L1 score of one keyframe during a query.
struct Tally {
  int shared_words = 0;
  double score = 0.0;
};

bool better(const PlaceCandidate& a, const PlaceCandidate& b) {
  if (a.accumulated_score != b.accumulated_score) return a.accumulated_score > b.accumulated_score;
  if (a.score != b.score) return a.score > b.score;
  return a.id < b.id;
}

}  // namespace

std::string KeyframeDatabaseConfig::validate() const {
  if (!(min_shared_words_ratio > 0.0 && min_shared_words_ratio <= 1.0)) {
    return "min_shared_words_ratio must be in (0, 1], got " +
           std::to_string(min_shared_words_ratio);
  }
  if (!(min_accumulated_score_ratio > 0.0 && min_accumulated_score_ratio <= 1.0)) {
    return "min_accumulated_score_ratio must be in (0, 1], got " +
           std::to_string(min_accumulated_score_ratio);
  }
  return "";
}

KeyframeDatabase::KeyframeDatabase(const KeyframeDatabaseConfig& config) : config_(config) {
  if (const std::string error = config.validate(); !error.empty()) {
    throw std::invalid_argument("KeyframeDatabaseConfig: " + error);
  }
}

void KeyframeDatabase::add(KeyframeId id, const BowVector& bow) {
  std::unique_lock lock(mutex_);
  eraseLocked(id);
  std::vector<WordId>& words = words_of_[id];
  words.reserve(bow.size());
  for (const auto& [word, weight] : bow) {
    inverted_[word].emplace_back(id, weight);
    words.push_back(word);
  }
}

bool KeyframeDatabase::erase(KeyframeId id) {
  std::unique_lock lock(mutex_);
  if (!words_of_.contains(id)) return false;
  eraseLocked(id);
  return true;
}

void KeyframeDatabase::eraseLocked(KeyframeId id) {
  const auto it = words_of_.find(id);
  if (it == words_of_.end()) return;
  for (const WordId word : it->second) {
    const auto list = inverted_.find(word);
    if (list == inverted_.end()) continue;
    std::erase_if(list->second, [id](const auto& entry) { return entry.first == id; });
    if (list->second.empty()) inverted_.erase(list);
  }
  words_of_.erase(it);
}

bool KeyframeDatabase::contains(KeyframeId id) const {
  std::shared_lock lock(mutex_);
  return words_of_.contains(id);
}

size_t KeyframeDatabase::size() const {
  std::shared_lock lock(mutex_);
  return words_of_.size();
}

void KeyframeDatabase::clear() {
  std::unique_lock lock(mutex_);
  inverted_.clear();
  words_of_.clear();
}

std::vector<PlaceCandidate> KeyframeDatabase::queryLoopCandidates(
    const BowVector& bow, double min_score, const std::vector<KeyframeId>& exclude,
    size_t max_results, const NeighbourFunction& neighbours) const {
  return query(bow, min_score, exclude, max_results, neighbours);
}

std::vector<PlaceCandidate> KeyframeDatabase::queryRelocalizationCandidates(
    const BowVector& bow, size_t max_results, const NeighbourFunction& neighbours) const {
  return query(bow, 0.0, {}, max_results, neighbours);
}

std::vector<PlaceCandidate> KeyframeDatabase::query(const BowVector& bow, double min_score,
                                                    const std::vector<KeyframeId>& exclude,
                                                    size_t max_results,
                                                    const NeighbourFunction& neighbours) const {
  const absl::flat_hash_set<KeyframeId> excluded(exclude.begin(), exclude.end());
  // 1.-2. Shared words and the L1 score sum_common min(q_w, k_w), from the inverted file.
  absl::flat_hash_map<KeyframeId, Tally> tallies;
  {
    std::shared_lock lock(mutex_);
    for (const auto& [word, query_weight] : bow) {
      const auto list = inverted_.find(word);
      if (list == inverted_.end()) continue;
      for (const auto& [id, weight] : list->second) {
        if (excluded.contains(id)) continue;
        Tally& tally = tallies[id];
        ++tally.shared_words;
        tally.score += std::min(query_weight, weight);
      }
    }
  }
  int max_shared = 0;
  for (const auto& [id, tally] : tallies) max_shared = std::max(max_shared, tally.shared_words);
  const double min_shared = config_.min_shared_words_ratio * max_shared;
  absl::flat_hash_map<KeyframeId, Tally> scored;
  for (const auto& [id, tally] : tallies) {
    if (tally.shared_words >= min_shared) {
      scored[id] = Tally{tally.shared_words, std::clamp(tally.score, 0.0, 1.0)};
    }
  }
  // 3. Minimum score; 4. covisibility groups (outside the lock).
  std::vector<PlaceCandidate> candidates;
  for (const auto& [id, tally] : scored) {
    if (tally.score < min_score) continue;
    PlaceCandidate c{id, tally.score, tally.score, tally.shared_words};
    if (neighbours) {
      for (const KeyframeId n : neighbours(id)) {
        const auto it = scored.find(n);
        if (it == scored.end() || n == id) continue;
        c.accumulated_score += it->second.score;
        if (it->second.score > c.score)
          c = {n, it->second.score, c.accumulated_score, it->second.shared_words};
      }
    }
    candidates.push_back(c);
  }
  if (neighbours) {
    double best = 0.0;
    for (const PlaceCandidate& c : candidates) best = std::max(best, c.accumulated_score);
    const double keep = config_.min_accumulated_score_ratio * best;
    std::erase_if(candidates,
                  [keep](const PlaceCandidate& c) { return c.accumulated_score < keep; });
    // A keyframe representing several groups is returned once, with its best group.
    std::sort(candidates.begin(), candidates.end(), better);
    absl::flat_hash_set<KeyframeId> seen;
    std::erase_if(candidates,
                  [&seen](const PlaceCandidate& c) { return !seen.insert(c.id).second; });
  } else {
    std::sort(candidates.begin(), candidates.end(), better);
  }
  if (max_results > 0 && candidates.size() > max_results) candidates.resize(max_results);
  return candidates;
}

}  // namespace cblox
