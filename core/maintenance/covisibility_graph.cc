#include "core/maintenance/covisibility_graph.h"

#include <algorithm>
#include <cmath>
#include <sstream>

namespace cblox {

std::string CovisibilityGraphConfig::validate() const {
  std::ostringstream error;
  if (min_shared_landmarks < 1) {
    error << "min_shared_landmarks must be >= 1, got " << min_shared_landmarks;
  } else if (!(min_shared_ratio >= 0.0 && min_shared_ratio <= 1.0)) {
    error << "min_shared_ratio must be in [0, 1], got " << min_shared_ratio;
  }
  return error.str();
}

void SubvolumeCovisibilityGraph::addSubvolume(int64_t subvolume) { landmarks_[subvolume]; }

void SubvolumeCovisibilityGraph::addWeight(int64_t a, int64_t b, int delta) {
  const auto k = key(a, b);
  const int w = (weights_[k] += delta);
  if (w == 0) weights_.erase(k);
}

bool SubvolumeCovisibilityGraph::addLandmark(int64_t s, uint64_t landmark) {
  if (!landmarks_[s].insert(landmark).second) return false;
  std::vector<int64_t>& holders = holders_[landmark];
  for (const int64_t t : holders) addWeight(s, t, 1);
  holders.push_back(s);
  return true;
}

size_t SubvolumeCovisibilityGraph::addLandmarks(int64_t subvolume,
                                                std::span<const uint64_t> landmark_ids) {
  addSubvolume(subvolume);
  size_t added = 0;
  for (const uint64_t l : landmark_ids) added += addLandmark(subvolume, l) ? 1 : 0;
  return added;
}

bool SubvolumeCovisibilityGraph::removeSubvolume(int64_t subvolume) {
  const auto it = landmarks_.find(subvolume);
  if (it == landmarks_.end()) return false;
  for (const uint64_t l : it->second) {
    std::vector<int64_t>& holders = holders_[l];
    holders.erase(std::find(holders.begin(), holders.end(), subvolume));
    for (const int64_t t : holders) addWeight(subvolume, t, -1);
    if (holders.empty()) holders_.erase(l);
  }
  landmarks_.erase(it);
  return true;
}

bool SubvolumeCovisibilityGraph::merge(int64_t kept, int64_t absorbed) {
  if (kept == absorbed || !contains(kept) || !contains(absorbed)) return false;
  // Detach absorbed first (its edges go), then give kept what it lacked.
  const absl::flat_hash_set<uint64_t> moved = landmarks_.at(absorbed);
  removeSubvolume(absorbed);
  for (const uint64_t l : moved) addLandmark(kept, l);
  return true;
}

size_t SubvolumeCovisibilityGraph::numLandmarks(int64_t subvolume) const {
  const auto it = landmarks_.find(subvolume);
  return it == landmarks_.end() ? 0 : it->second.size();
}

int SubvolumeCovisibilityGraph::weight(int64_t a, int64_t b) const {
  if (a == b) return 0;
  const auto it = weights_.find(key(a, b));
  return it == weights_.end() ? 0 : it->second;
}

std::vector<std::pair<int64_t, int>> SubvolumeCovisibilityGraph::neighbours(
    int64_t subvolume) const {
  std::vector<std::pair<int64_t, int>> out;
  for (const auto& [k, w] : weights_) {
    if (k.first == subvolume) out.emplace_back(k.second, w);
    if (k.second == subvolume) out.emplace_back(k.first, w);
  }
  std::sort(out.begin(), out.end());
  return out;
}

std::vector<CovisibilityCandidate> SubvolumeCovisibilityGraph::candidates(
    const CovisibilityGraphConfig& config) const {
  std::vector<CovisibilityCandidate> out;
  for (const auto& [k, w] : weights_) {
    const size_t na = numLandmarks(k.first), nb = numLandmarks(k.second);
    if (w < config.min_shared_landmarks) continue;
    if (static_cast<double>(w) < config.min_shared_ratio * static_cast<double>(std::min(na, nb)))
      continue;
    out.push_back(CovisibilityCandidate{k.first, k.second, w, na, nb});
  }
  std::sort(out.begin(), out.end(), [](const auto& x, const auto& y) {
    if (x.shared != y.shared) return x.shared > y.shared;
    return std::pair{x.a, x.b} < std::pair{y.a, y.b};
  });
  return out;
}

}  // namespace cblox
