#pragma once

// The tracker's id lease (README, "Tracker map format"): keyframe and landmark ids the
// tracker may have published since its last checkpoint. A resumed tracker continues above
// them, so an id another process saw before a crash never names a different keyframe or
// landmark. Written (atomically, durably) before the first id beyond the previous lease is
// published.

#include <cstdint>
#include <optional>
#include <string>

namespace cblox {

inline constexpr char kIdLeaseFileName[] = "keyframe_ids.lease";

/// Ids below these floors may have been used in map epoch `map_epoch`.
struct IdLease {
  int32_t map_epoch = 0;
  int64_t keyframe_floor = 0;
  uint64_t landmark_floor = 0;
  bool operator==(const IdLease&) const = default;
};

/// Writes <dir>/keyframe_ids.lease atomically (writeFileAtomically, which fsyncs the file and
/// the directory). False with the message in *error (if non-null). Thread-safe.
bool writeIdLease(const std::string& dir, const IdLease& lease, std::string* error);

/// Reads <dir>/keyframe_ids.lease. std::nullopt with an empty *error when there is none; with
/// "<path>: <what is wrong>" when it is unreadable, damaged or inconsistent (negative epoch or
/// keyframe floor). Thread-safe.
std::optional<IdLease> readIdLease(const std::string& dir, std::string* error);

}  // namespace cblox
