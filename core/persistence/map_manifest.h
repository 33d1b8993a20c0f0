#pragma once

#include <cstdint>
#include <map>
#include <optional>
#include <string>
#include <vector>

#include "core/geometry/se3.h"
#include "core/maintenance/fusion_scheduler_state.h"
#include "core/persistence/submap_file.h"
#include "core/submap/submap.h"
#include "core/submap/submap_collection.h"

namespace cblox {

/// Newest manifest format version this build writes; it reads 1 to 3. Version 2 appends the
/// map maintenance section (covisibility landmark sets, pair back-offs); a version 1 manifest
/// reads as one with an empty maintenance section. Version 3 keeps the landmark sets per
/// keyframe; a version 2 subvolume's one set reads as that of KeyframeLandmarks::
/// kUnknownKeyframe.
inline constexpr uint32_t kManifestVersion = 3;
/// File name of the manifest inside a map directory.
inline constexpr char kManifestFileName[] = "manifest.cbmap";

/// Everything about one submap except its voxels (those are in `file`).
struct SubmapRecord {
  SubmapId id = 0;
  KeyframeId anchor_keyframe = 0;
  int64_t creation_time_ns = 0;
  Transformationd T_G_M;
  bool finished = false;                 ///< false for the active submap only
  std::vector<KeyframeId> keyframe_ids;  ///< ascending, the anchor included
  SubmapFileInfo file;                   ///< the file holding its voxels
};

/// The manifest of a map directory: the collection-level data and the list of submap files
/// that make up the map. A reader trusts only the files listed here.
struct MapManifest {
  /// Incremented by every checkpoint; the submap files it writes carry it in their name.
  uint64_t generation = 0;
  SubmapCollectionConfig config;
  /// SubmapCollection::nextSubmapId() when saved (ids of removed submaps are not reused).
  SubmapId next_submap_id = 0;
  std::optional<SubmapId> active_submap_id;  ///< none when no submap was active
  std::vector<SubmapRecord> submaps;         ///< ascending ids
  /// Free-form counters of the caller (e.g. frames integrated, fusions), saved verbatim.
  std::map<std::string, int64_t> counters;
  /// The map maintenance's state (version 2 and later; empty when read from version 1): the
  /// keyframes' landmark sets of the covisibility graph and the back-off of rejected pairs,
  /// for listed submaps.
  FusionSchedulerState maintenance;

  /// Empty when consistent, otherwise what is wrong: invalid config, ids not strictly
  /// increasing or not below next_submap_id, a non-finite pose, keyframe ids not ascending
  /// or without the anchor, a file name that is not a submapFileName() of its submap, more
  /// than one unfinished submap, an active id that is not the unfinished submap (or an
  /// unfinished submap that is not active), a counter name empty or longer than 256 bytes,
  /// a maintenance section that is not well-formed (FusionSchedulerState::validate) or names
  /// a submap that is not listed.
  /// Thread-safe (pure).
  std::string validate() const;
};

/// The manifest's complete file bytes (header and payload; README, "Map file format"):
///
///     uint64 generation   f32 voxel size   int32 voxels per side   int64 next submap id
///     uint8 has active    int64 active id (0 when none)
///     uint32 submap count, then per submap:
///       int64 id  int64 anchor keyframe  int64 creation time (ns)
///       f64 tx ty tz qx qy qz qw (T_G_M)  uint8 finished
///       uint32 keyframe count, int64 each
///       uint32 length + file name bytes  uint64 file size  uint64 payload XXH64
///       uint64 block count
///     uint32 counter count, then per counter: uint32 length + name bytes, int64 value
///   version 3 appends the maintenance section:
///     uint32 subvolume count, then per subvolume (ascending ids, each a listed submap):
///       int64 id  uint32 keyframe count, then per keyframe (ascending ids; -1: not known):
///         int64 keyframe id  uint32 landmark count
///         landmark ids ascending as uvarints (LEB128): the first as is, then differences (>= 1)
///     uint32 back-off count, then per pair (ascending (older, newer), both listed):
///       int64 older  int64 newer  int32 rejections by q in a row  f64 seconds left to wait
///   (version 2 had, per subvolume, int64 id and one landmark set, in place of the keyframes)
///
/// Precondition: manifest.validate() is empty. Thread-safe (pure).
std::string encodeManifest(const MapManifest& manifest);

/// Writes <dir>/manifest.cbmap atomically (writeFileAtomically). Returns false with a message
/// naming the path in *error (if non-null) when the manifest is inconsistent (validate()) or
/// cannot be written. Thread-safe (no shared state); one writer per directory at a time.
bool writeManifest(const MapManifest& manifest, const std::string& dir, std::string* error);

/// Reads and verifies <dir>/manifest.cbmap (format version 1, 2 or 3): header (readMapFile), every
/// count and length bounded by the bytes that remain before anything is allocated, no bytes left
/// over, and validate(). Returns std::nullopt with "<path>: <what is wrong>" in *error (if
/// non-null) otherwise. Does not open the submap files (loadMap does). Thread-safe (no shared
/// state).
std::optional<MapManifest> readManifest(const std::string& dir, std::string* error);

}  // namespace cblox
