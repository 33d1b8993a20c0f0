#pragma once

#include <cstddef>
#include <cstdint>
#include <span>
#include <string>
#include <utility>
#include <vector>

#include <absl/container/flat_hash_map.h>
#include <absl/container/flat_hash_set.h>

namespace cblox {

/// Which edges of the subvolume covisibility graph are fusion candidates.
struct CovisibilityGraphConfig {
  /// An edge is a candidate when the two subvolumes share at least min_shared_landmarks
  /// landmarks (>= 1; 30) ...
  int min_shared_landmarks = 30;
  /// ... and at least this fraction of the smaller of the two landmark sets, in [0, 1]
  /// (0.04; 0 = the absolute bound alone; 0.05 until the frames rule became the default,
  /// under which a revisited subvolume's set grows and the room's one pair shared 4.7 %).
  /// Measured on the simulated room: with 5 keyframes per subvolume (~2000 landmarks each,
  /// 2 laps) neighbouring subvolumes share 13-22 % of the smaller set, a revisit after loop
  /// closure 22 %; with 10 keyframes per subvolume (~4000-5000 landmarks, 3 laps) revisits
  /// share 7-10 %; unrelated ones 0-1 landmarks.
  /// The set grows with the subvolume while the overlap with one revisit does not, so the
  /// bound is loose: the covariance test (q_min) decides.
  double min_shared_ratio = 0.04;

  /// Empty when valid, else a message naming the first bad field. Thread-safe.
  std::string validate() const;
};

/// A candidate pair for fusion: a < b, their shared landmark count and set sizes.
struct CovisibilityCandidate {
  int64_t a = 0;
  int64_t b = 0;
  int shared = 0;
  size_t landmarks_a = 0;
  size_t landmarks_b = 0;
};

/// The covisibility graph over subvolumes (the map maintenance's view of the sparse map): a
/// vertex per subvolume holding L, the set of landmark ids observed by the keyframes that
/// contributed to it, and edge weights W_ij = |L_i ∩ L_j|, kept exact incrementally as
/// keyframes add landmarks and as subvolumes fuse (the kept vertex takes the union).
/// Subvolume ids are the collection's SubmapId; landmark ids the sparse map's LandmarkId.
///
/// Cost: adding landmark l to subvolume s touches the other subvolumes that hold l;
/// merging touches the absorbed subvolume's landmarks. Memory: one entry per (landmark,
/// subvolume) membership and per non-zero edge.
/// Thread-safety: none (owned by the mapper's maintenance thread); const members may run
/// concurrently with each other.
class SubvolumeCovisibilityGraph {
 public:
  /// Adds a vertex with no landmarks; nothing happens if it exists.
  void addSubvolume(int64_t subvolume);
  /// Adds landmark ids (duplicates and ones already held are ignored) to the subvolume,
  /// creating it if needed, and updates its edge weights. Returns how many were new to it.
  size_t addLandmarks(int64_t subvolume, std::span<const uint64_t> landmark_ids);
  /// `absorbed` is fused into `kept`: kept's set becomes the union, absorbed disappears with
  /// its edges. Returns false (nothing changed) when either is unknown or they are the same.
  bool merge(int64_t kept, int64_t absorbed);
  /// Removes a vertex and its edges; false when unknown.
  bool removeSubvolume(int64_t subvolume);

  bool contains(int64_t subvolume) const { return landmarks_.contains(subvolume); }
  size_t numSubvolumes() const { return landmarks_.size(); }
  size_t numEdges() const { return weights_.size(); }
  /// |L_s| (0 for an unknown subvolume).
  size_t numLandmarks(int64_t subvolume) const;
  /// W_ab = |L_a ∩ L_b| (0 when unknown or a == b).
  int weight(int64_t a, int64_t b) const;
  /// Subvolumes sharing at least one landmark with `subvolume`, with the weights, by id.
  std::vector<std::pair<int64_t, int>> neighbours(int64_t subvolume) const;
  /// Edges that meet the config's bounds, by decreasing weight (then by (a, b)).
  std::vector<CovisibilityCandidate> candidates(const CovisibilityGraphConfig& config) const;

 private:
  static std::pair<int64_t, int64_t> key(int64_t a, int64_t b) {
    return a < b ? std::pair{a, b} : std::pair{b, a};
  }
  void addWeight(int64_t a, int64_t b, int delta);
  /// Adds one landmark to s's set (s must exist); true if it was new.
  bool addLandmark(int64_t s, uint64_t landmark);

  absl::flat_hash_map<int64_t, absl::flat_hash_set<uint64_t>> landmarks_;  // L per vertex
  absl::flat_hash_map<uint64_t, std::vector<int64_t>> holders_;    // subvolumes per landmark
  absl::flat_hash_map<std::pair<int64_t, int64_t>, int> weights_;  // non-zero W, a < b
};

}  // namespace cblox
