#pragma once

#include <chrono>
#include <cstddef>
#include <cstdint>
#include <map>
#include <optional>
#include <string>

#include "core/persistence/map_manifest.h"
#include "core/persistence/map_store.h"
#include "core/submap/submap_collection.h"

namespace cblox {

/// What one MapCheckpointer::checkpoint() did. Plain value type.
struct MapCheckpointReport {
  uint64_t generation = 0;     ///< the generation of the manifest written
  size_t submaps = 0;          ///< submaps the manifest lists
  size_t submaps_written = 0;  ///< submap files written by this checkpoint
  size_t submaps_reused = 0;   ///< submap files of the previous checkpoint listed again
  uint64_t bytes_written = 0;  ///< bytes of the submap files written and of the manifest
  double milliseconds = 0.0;   ///< wall time of the checkpoint
};

/// Periodic incremental checkpoints of one SubmapCollection into one map directory
/// (core/persistence/map_store.h, README "Map file format"). It remembers the manifest it
/// last committed and the Submap::revision() each submap had when its file was last written;
/// checkpoint() rewrites only the submaps that are new or whose revision changed since, then
/// commits a new manifest (writeMapCheckpoint), which no longer lists removed (fused)
/// submaps. The first checkpoint of an instance writes every submap, unless adoptLoaded()
/// told it that the collection was just loaded from this very directory (a resume): then the
/// loaded files are listed again and only what changed since the load is written.
///
/// Errors: a failed checkpoint leaves the committed map and this object's memory unchanged
/// (the next one retries the same submaps).
/// Thread-safety: not thread-safe; one instance per directory and one caller at a time, on a
/// thread allowed to read finished layers (the mapper's fusion worker; see writeMapCheckpoint).
/// The collection may change meanwhile.
class MapCheckpointer {
 public:
  /// `dir`: the checkpoint directory (created by the first checkpoint if missing).
  explicit MapCheckpointer(std::string dir);

  /// Writes a checkpoint of `collection` with `counters` and the maintenance state (see
  /// writeMapCheckpoint; `maintenance` may be empty) in the manifest. Returns what was
  /// written, or std::nullopt with writeMapCheckpoint's message (naming the file) in *error
  /// (if non-null).
  std::optional<MapCheckpointReport> checkpoint(const SubmapCollection& collection,
                                                const std::map<std::string, int64_t>& counters,
                                                const MaintenanceStateSource& maintenance,
                                                std::string* error);

  /// After loadMap(dir(), ...) into `collection` and before anything changes it: takes
  /// `manifest` (the one loaded) as the last committed checkpoint and the submaps' current
  /// revisions as those of its files, so the next checkpoint reuses them. Submaps the manifest
  /// does not list are written next time as new.
  void adoptLoaded(const MapManifest& manifest, const SubmapCollection& collection);

  /// Test only (the crash test): every later checkpoint sleeps this long before each submap
  /// file it writes and before its manifest (writeMapCheckpoint's pause_before_each_file).
  /// 0 = off (the default).
  void setPauseBeforeEachFile(std::chrono::milliseconds pause) { pause_ = pause; }

  const std::string& dir() const { return dir_; }
  /// The manifest last committed by this instance; std::nullopt before the first success.
  const std::optional<MapManifest>& lastManifest() const { return previous_; }

 private:
  const std::string dir_;
  std::optional<MapManifest> previous_;
  std::chrono::milliseconds pause_{0};
  // Submap id -> its revision() when its file (listed in previous_) was written.
  std::map<SubmapId, uint64_t> written_revisions_;
};

}  // namespace cblox
