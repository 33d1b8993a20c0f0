#pragma once

#include <chrono>
#include <cstddef>
#include <cstdint>
#include <functional>
#include <map>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "core/maintenance/fusion_scheduler_state.h"
#include "core/persistence/map_manifest.h"
#include "core/submap/submap_collection.h"

namespace cblox {

/// Gives the map maintenance's state (FusionScheduler::exportState) for a checkpoint; called
/// once, right after the collection's snapshot, so the state is at least as new as the map
/// it goes with. May be empty (no maintenance state).
using MaintenanceStateSource = std::function<FusionSchedulerState()>;

/// What a save or checkpoint did.
struct MapSaveReport {
  uint64_t generation = 0;     ///< the generation of the manifest written
  size_t files_written = 0;    ///< submap files written by this call
  size_t files_reused = 0;     ///< submap files of the previous manifest listed again
  uint64_t bytes_written = 0;  ///< bytes of the submap files written and of the manifest
  size_t files_removed = 0;    ///< unlisted files removed afterwards (removeUnlistedMapFiles)
};

/// What loadMap did.
struct MapLoadReport {
  uint64_t generation = 0;  ///< the manifest's generation
  size_t submaps = 0;
  uint64_t blocks = 0;
  uint64_t bytes_read = 0;                  ///< manifest and submap files
  std::map<std::string, int64_t> counters;  ///< the caller's counters, as saved
  FusionSchedulerState maintenance;         ///< the map maintenance's state, as saved
  size_t unlisted_files = 0;                ///< files in the directory the manifest does not list
};

/// Writes a checkpoint of `collection` into the map directory `dir` (created if missing):
/// first a submap file (writeSubmapFile) for every submap in `submaps_to_write`, and for every
/// submap that `previous` (the manifest this process last wrote into `dir`; null for none) does
/// not list or whose listed file is missing or has another size; the other submaps keep the
/// file `previous` lists. Then, last, the manifest (writeManifest) with the collection's
/// state (SubmapCollection::snapshot(): poses, keyframes, active submap, next id), `counters`,
/// the maintenance state from `maintenance` restricted to the listed submaps, and a generation
/// above every one in the directory, so no file the committed manifest lists
/// is overwritten: a crash at any point leaves the previous map loadable. Finally it removes
/// the files no longer listed (removeUnlistedMapFiles; a failure there is not an error).
/// Returns the manifest written (pass it as `previous` next time), or std::nullopt with a
/// message naming the file in *error (if non-null); then the committed map is unchanged.
/// `report` may be null. Ids in `submaps_to_write` that are not in the collection are ignored.
/// `pause_before_each_file` (test only, 0 otherwise) sleeps before each submap file and before
/// the manifest is written, widening the window in which a crash interrupts the checkpoint.
/// Thread-safety: see writeSubmapFile (call it on the fusion worker, or while nothing modifies
/// finished layers); the collection may change meanwhile (the manifest is a snapshot). One
/// writer per directory at a time.
std::optional<MapManifest> writeMapCheckpoint(
    const SubmapCollection& collection, const std::string& dir, const MapManifest* previous,
    const std::vector<SubmapId>& submaps_to_write, const std::map<std::string, int64_t>& counters,
    const MaintenanceStateSource& maintenance, MapSaveReport* report, std::string* error,
    std::chrono::milliseconds pause_before_each_file = {});

/// Full save: writeMapCheckpoint with no previous manifest, so every submap file is written.
/// Same contract and thread-safety.
std::optional<MapManifest> saveMap(const SubmapCollection& collection, const std::string& dir,
                                   const std::map<std::string, int64_t>& counters,
                                   const MaintenanceStateSource& maintenance, MapSaveReport* report,
                                   std::string* error);

/// Loads the map in `dir` into `into`, which must be empty and not have assigned ids at or
/// above the first saved id, with the same layer geometry as the manifest (voxel size, voxels
/// per side; compared exactly). Reads the manifest (readManifest) and every submap file it
/// lists (readSubmapFile: checksums, sizes, bounds), ignoring every other file (leftover
/// temporaries, files of older generations). Only when all of them are valid it restores the
/// submaps (SubmapCollection::restoreSubmap: ids, poses, anchors, creation times, finished
/// flags, the active submap), their keyframes and the next id, and returns the counters and
/// the maintenance state in `report` (the caller restores those); otherwise it returns false with
/// "<path>: <what is wrong>" in *error (if non-null) and `into` is unchanged. `report` may be
/// null. The layers are decoded in memory before they go in (no copy). Thread-safe (no shared
/// state), provided no other thread adds submaps to `into` during the load.
bool loadMap(const std::string& dir, SubmapCollection* into, MapLoadReport* report,
             std::string* error);

/// loadMap into a new collection configured as the manifest says. nullptr (and *error) on any
/// error. Thread-safe (no shared state).
std::unique_ptr<SubmapCollection> loadMap(const std::string& dir, MapLoadReport* report,
                                          std::string* error);

/// Removes from `dir` the submap files (submapFileName) that `manifest` does not list and the
/// temporary files ("submap_*.tmp.*", "manifest.cbmap.tmp.*") of interrupted writes; other
/// files are never touched. Call only with the manifest committed in `dir`, and with no other
/// writer in the directory. Returns the number removed; the first failure (if any) goes to
/// *error (if non-null) and the rest are still attempted. Thread-safe (no shared state).
size_t removeUnlistedMapFiles(const MapManifest& manifest, const std::string& dir,
                              std::string* error);

}  // namespace cblox
