#pragma once

// The payload of local_grid_t (lcmtypes/local_grid_t.lcm): a LocalGrid's states and
// distances, packed and zlib-compressed for the bus, and unpacked again with every size
// checked before anything is allocated.

#include <string>

#include <cblox/local_grid_t.hpp>

#include "core/mapping/planning_service.h"

namespace cblox {

/// The message of `sample`: payload one int8 state per cell, then one little-endian int16
/// distance per cell in millimetres (rounded, clamped to [-32767, 32767]; -32768 where
/// unknown), compressed with zlib at `level` (1 fast .. 9 small; 0 = ENCODING_RAW).
/// Throws std::invalid_argument when the grid's sizes disagree or level is outside [0, 9].
local_grid_t encodeLocalGrid(const LocalGridSample& sample, int level = 1);

/// The grid of `msg` into *out (states and distances in metres, NaN where unknown). Refused
/// (false, *error says why, *out unchanged) when a size is < 1, the cells exceed
/// PlanningMap::kMaxGridCells, resolution or origin is not finite, raw_size is not 3 bytes a
/// cell, the encoding is unknown, the data does not inflate to exactly raw_size bytes, or a
/// state is not one of local_grid_t's. Never allocates more than raw_size bytes beyond the
/// grid's own vectors, which are bounded first. Thread-safe (pure).
bool decodeLocalGrid(const local_grid_t& msg, LocalGridSample* out, std::string* error);

}  // namespace cblox
