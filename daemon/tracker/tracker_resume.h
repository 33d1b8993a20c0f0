#pragma once

// What a tracker resumes from at start (config/tracker.yaml `checkpoint`): the saved sparse map
// and the id lease of its checkpoint directory, and the rule that keeps published ids unique
// across crashes (IdLeaseKeeper).

#include <cstdint>
#include <optional>
#include <string>

#include "core/persistence/id_lease.h"
#include "core/persistence/sparse_map_file.h"

namespace cblox {

/// The starting point of a resumed tracker. Plain value type.
struct TrackerResume {
  /// The map to continue (absent: start a new map in map_epoch).
  std::optional<TrackerMapState> map;
  /// The epoch to work in: the map's, or (no map to continue) one after anything the
  /// directory says was published.
  int32_t map_epoch = 0;
  /// The first keyframe / landmark ids the resumed map may hand out (SlamSystem::restore).
  int64_t keyframe_floor = 0;
  uint64_t landmark_floor = 0;
  /// The map's index, for TrackerMapCheckpointer::adoptLoaded.
  TrackerMapIndex index;
  /// One line for the log: what was found and what will happen.
  std::string description;
};

/// Reads the checkpoint directory `dir`: the tracker map (loadTrackerMap) and the id lease.
/// - neither: std::nullopt, empty *error (a first start);
/// - a map, and a lease of its epoch or none: continue the map above the lease's floors;
/// - a lease of another epoch than the map's, or a lease without a map (the tracker crashed
///   before its first checkpoint, or after starting a newer map): the map cannot be
///   continued safely, so a new map starts in the epoch after every epoch seen;
/// - a map or lease that cannot be read: std::nullopt with the message in *error.
/// Thread-safe (no shared state).
std::optional<TrackerResume> loadTrackerResume(const std::string& dir, std::string* error);

/// Keeps the id lease ahead of the ids the tracker publishes: before a keyframe goes out whose
/// id or newest landmark id reaches the lease (or that is of another epoch), a new lease
/// (this id + keyframe_margin, newest landmark + landmark_margin) is written durably.
/// Thread-safety: not thread-safe (the tracking thread publishes keyframes).
class IdLeaseKeeper {
 public:
  IdLeaseKeeper(std::string dir, std::optional<IdLease> current, int64_t keyframe_margin = 64,
                uint64_t landmark_margin = 1 << 16);
  /// Covers keyframe `id` with newest landmark id `newest_landmark` (0 when none) in `epoch`.
  /// Returns false (the lease may be behind; the message in *error) when the lease could not
  /// be written.
  bool cover(int32_t epoch, int64_t id, uint64_t newest_landmark, std::string* error);
  /// Lease writes so far.
  uint64_t renewals() const { return renewals_; }

 private:
  std::string dir_;
  std::optional<IdLease> lease_;
  int64_t keyframe_margin_;
  uint64_t landmark_margin_;
  uint64_t renewals_ = 0;
};

}  // namespace cblox
