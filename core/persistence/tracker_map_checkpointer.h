#pragma once

#include <chrono>
#include <cstddef>
#include <cstdint>
#include <map>
#include <optional>
#include <string>
#include <vector>

#include "core/persistence/sparse_map_file.h"

namespace cblox {

/// What one TrackerMapCheckpointer::checkpoint() did. Plain value type.
struct TrackerCheckpointReport {
  uint64_t generation = 0;       ///< of the index written
  size_t keyframes = 0;          ///< keyframes (culled ones included) the index lists
  size_t keyframes_written = 0;  ///< keyframes whose features went into a new chunk file
  size_t landmarks = 0;
  uint64_t bytes_written = 0;  ///< chunk file and index
  double milliseconds = 0.0;
};

/// Periodic incremental checkpoints of the tracker's map into one directory (sparse_map_file.h):
/// a keyframe's features are immutable, so they are written once, into the chunk file of the
/// checkpoint that first saw the keyframe; every checkpoint rewrites only the index (poses,
/// graph, landmarks), atomically and last. After the index is committed, chunk files it no
/// longer lists (every keyframe in them culled, or an older map) are deleted. Chunk files get
/// generations above every one present in the directory, so a committed file is never
/// overwritten, and a crash at any point leaves the previous index and its files loadable.
/// Temporary files a crash left are deleted after the next commit too.
///
/// A new map epoch (the tracker started a new map) starts over: the next checkpoint writes
/// every keyframe of the new map. Errors leave the committed map and this object unchanged.
/// Thread-safety: not thread-safe; one instance per directory, one caller at a time.
class TrackerMapCheckpointer {
 public:
  /// `dir`: the checkpoint directory (created by the first checkpoint if missing).
  explicit TrackerMapCheckpointer(std::string dir);

  /// After `state` was loaded from this very directory (loadTrackerMap with its index): the
  /// next checkpoint lists the loaded chunks again instead of rewriting their features.
  void adoptLoaded(const TrackerMapIndex& index);

  /// Writes a checkpoint of `state` (its generation field is ignored: the checkpoint numbers
  /// it). Returns what was written, or std::nullopt with the message naming the file in
  /// *error (if non-null).
  std::optional<TrackerCheckpointReport> checkpoint(const TrackerMapState& state,
                                                    std::string* error);

  /// Test only (scripts/crash_test.sh): every later checkpoint sleeps this long before its
  /// chunk file and before its index, so that a kill lands inside a checkpoint write often.
  void setPauseBeforeEachFile(std::chrono::milliseconds pause) { pause_ = pause; }

  const std::string& dir() const { return dir_; }
  /// Generation of the last committed index (0: none by this instance or adopted).
  uint64_t generation() const { return generation_; }

 private:
  uint64_t nextGeneration() const;
  void deleteUnlistedChunks(const std::vector<KeyframeChunkRef>& listed) const;

  std::string dir_;
  std::chrono::milliseconds pause_{0};
  uint64_t generation_ = 0;
  int32_t map_epoch_ = -1;  // of the committed chunks (-1: none)
  std::vector<KeyframeChunkRef> chunks_;
  std::map<KeyframeId, size_t> chunk_of_;  // keyframe -> index into chunks_
};

}  // namespace cblox
