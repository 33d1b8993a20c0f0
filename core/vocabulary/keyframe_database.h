#pragma once

#include <cstddef>
#include <cstdint>
#include <functional>
#include <shared_mutex>
#include <string>
#include <utility>
#include <vector>

#include <absl/container/flat_hash_map.h>

#include "core/vocabulary/bow_vector.h"

namespace cblox {

/// Keyframe identifier (the same type as in core/submap/submap.h).
using KeyframeId = int64_t;

/// Settings of the candidate selection (ORB-SLAM2's constants by default).
struct KeyframeDatabaseConfig {
  /// Only keyframes sharing at least this fraction of the largest number of words any
  /// keyframe shares with the query are scored. (0, 1]. Default 0.8.
  double min_shared_words_ratio = 0.8;
  /// With a neighbour function: groups whose accumulated score is at least this fraction of
  /// the best group's are returned. (0, 1]. Default 0.75.
  double min_accumulated_score_ratio = 0.75;

  /// Empty when valid, otherwise a message naming the offending field. Thread-safe.
  std::string validate() const;
};

/// One place-recognition candidate.
struct PlaceCandidate {
  KeyframeId id = 0;
  /// L1 score (scoreL1) of this keyframe against the query, in [0, 1].
  double score = 0.0;
  /// Without a neighbour function: equal to `score`. With one: the sum of the scores of the
  /// group (a candidate and its neighbours that were scored); `id` is the group's best.
  double accumulated_score = 0.0;
  /// Words this keyframe shares with the query.
  int shared_words = 0;
};

/// The inverted file of the keyframes' BoW vectors (word -> keyframes with their weight of
/// that word), queried for loop and relocalisation candidates like ORB-SLAM2's
/// KeyFrameDatabase:
///   1. count, per keyframe, the words it shares with the query (walking only the query's
///      words' lists; excluded keyframes are skipped);
///   2. score (L1, accumulated from the lists' weights) only the keyframes sharing at least
///      min_shared_words_ratio x the largest count;
///   3. loop queries drop keyframes scoring below min_score;
///   4. with a NeighbourFunction (the caller's covisibility graph, e.g. the 10 best covisible
///      keyframes), each remaining candidate's score is accumulated with the scores of its
///      neighbours that were scored in step 2, the group is represented by its best-scoring
///      keyframe, and groups reaching min_accumulated_score_ratio x the best accumulated
///      score are kept (duplicates merged). Without one, candidates are returned by score:
///      covisibility is then the caller's business.
/// Results are sorted by accumulated_score (then score, then id), best first.
///
/// Thread-safety: all methods are thread-safe (internal reader-writer mutex): the loop
/// closing thread and the tracking thread may query while the local mapping thread adds and
/// culls keyframes. The NeighbourFunction is called from the querying thread WITHOUT the
/// database's mutex held, so it may lock the map (no lock-order inversion with add/erase).
class KeyframeDatabase {
 public:
  /// Neighbours of a keyframe (e.g. its best covisible keyframes); may return unknown ids.
  using NeighbourFunction = std::function<std::vector<KeyframeId>(KeyframeId)>;

  /// Throws std::invalid_argument with KeyframeDatabaseConfig::validate()'s message.
  explicit KeyframeDatabase(const KeyframeDatabaseConfig& config = {});

  /// Adds a keyframe's BoW vector (replacing the one stored for `id`, if any).
  void add(KeyframeId id, const BowVector& bow);
  /// Removes a keyframe; false if it was not stored.
  bool erase(KeyframeId id);
  bool contains(KeyframeId id) const;
  size_t size() const;
  void clear();

  /// Loop candidates for a keyframe with BoW vector `bow`: keyframes other than `exclude`
  /// (the query keyframe and its covisible neighbours) scoring >= min_score (ORB-SLAM2 uses
  /// the lowest score of the query against its covisible keyframes), at most max_results
  /// (0 = all).
  std::vector<PlaceCandidate> queryLoopCandidates(const BowVector& bow, double min_score,
                                                  const std::vector<KeyframeId>& exclude,
                                                  size_t max_results,
                                                  const NeighbourFunction& neighbours = {}) const;

  /// Relocalisation candidates for a frame: as a loop query without exclusions and without a
  /// minimum score, at most max_results (0 = all).
  std::vector<PlaceCandidate> queryRelocalizationCandidates(
      const BowVector& bow, size_t max_results, const NeighbourFunction& neighbours = {}) const;

 private:
  std::vector<PlaceCandidate> query(const BowVector& bow, double min_score,
                                    const std::vector<KeyframeId>& exclude, size_t max_results,
                                    const NeighbourFunction& neighbours) const;
  void eraseLocked(KeyframeId id);

  KeyframeDatabaseConfig config_;
  mutable std::shared_mutex mutex_;
  absl::flat_hash_map<WordId, std::vector<std::pair<KeyframeId, double>>> inverted_;
  absl::flat_hash_map<KeyframeId, std::vector<WordId>> words_of_;
};

}  // namespace cblox
