#include "daemon/common/local_grid_codec.h"

#include <zlib.h>

#include <cmath>
#include <cstdint>
#include <limits>
#include <stdexcept>
#include <vector>

#include "core/common/text_format.h"

namespace cblox {

namespace {

constexpr int16_t kUnknownMm = std::numeric_limits<int16_t>::min();

// The wire's states are VoxelState's values.
static_assert(static_cast<int>(VoxelState::kUnknown) == local_grid_t::UNKNOWN);
static_assert(static_cast<int>(VoxelState::kFree) == local_grid_t::FREE);
static_assert(static_cast<int>(VoxelState::kOccupied) == local_grid_t::OCCUPIED);

int16_t millimetres(VoxelState state, float distance_m) {
  if (state == VoxelState::kUnknown || !std::isfinite(distance_m)) return kUnknownMm;
  const double mm = std::round(static_cast<double>(distance_m) * 1000.0);
  return static_cast<int16_t>(std::clamp(mm, -32767.0, 32767.0));
}

}  // namespace

local_grid_t encodeLocalGrid(const LocalGridSample& sample, int level) {
  const LocalGrid& g = sample.grid;
  if (level < 0 || level > 9) throw std::invalid_argument("zlib level must be in [0, 9]");
  if ((g.size.array() < 1).any()) throw std::invalid_argument("a local grid has >= 1 cell per axis");
  const size_t n = static_cast<size_t>(g.size.x()) * static_cast<size_t>(g.size.y()) *
                   static_cast<size_t>(g.size.z());
  if (g.state.size() != n || g.distance.size() != n) {
    throw std::invalid_argument("the local grid's states and distances must have one entry a cell");
  }
  std::vector<uint8_t> raw(3 * n);
  for (size_t c = 0; c < n; ++c) {
    raw[c] = static_cast<uint8_t>(g.state[c]);
    const uint16_t mm = static_cast<uint16_t>(millimetres(g.state[c], g.distance[c]));
    raw[n + 2 * c] = static_cast<uint8_t>(mm & 0xFF);
    raw[n + 2 * c + 1] = static_cast<uint8_t>(mm >> 8);
  }
  local_grid_t msg;
  msg.utime = sample.utime;
  msg.map_epoch = sample.map_epoch;
  msg.pose_utime = sample.pose_utime;
  for (int a = 0; a < 3; ++a) {
    msg.origin[a] = g.origin[a];
    msg.size[a] = g.size[a];
  }
  msg.resolution = g.resolution;
  msg.max_distance_m = sample.max_distance_m;
  msg.raw_size = static_cast<int32_t>(raw.size());
  if (level == 0) {
    msg.encoding = local_grid_t::ENCODING_RAW;
    msg.data = std::move(raw);
  } else {
    msg.encoding = local_grid_t::ENCODING_ZLIB;
    uLongf packed = compressBound(static_cast<uLong>(raw.size()));
    msg.data.resize(packed);
    if (compress2(msg.data.data(), &packed, raw.data(), static_cast<uLong>(raw.size()), level) !=
        Z_OK) {
      throw std::runtime_error("zlib compress2 failed");
    }
    msg.data.resize(packed);
  }
  msg.num_bytes = static_cast<int32_t>(msg.data.size());
  return msg;
}

bool decodeLocalGrid(const local_grid_t& msg, LocalGridSample* out, std::string* error) {
  double cells = 1.0;
  for (int a = 0; a < 3; ++a) {
    if (msg.size[a] < 1) {
      *error = "size[" + std::to_string(a) + "] is " + std::to_string(msg.size[a]) + ", not >= 1";
      return false;
    }
    cells *= static_cast<double>(msg.size[a]);
    if (!std::isfinite(msg.origin[a])) {
      *error = "origin is not finite";
      return false;
    }
  }
  if (cells > static_cast<double>(PlanningMap::kMaxGridCells)) {
    *error = significant(cells, 3) + " cells, more than " +
             std::to_string(PlanningMap::kMaxGridCells);
    return false;
  }
  if (!std::isfinite(msg.resolution) || !(msg.resolution > 0.0)) {
    *error = "resolution is not finite and > 0";
    return false;
  }
  const size_t n = static_cast<size_t>(cells);
  if (msg.raw_size < 0 || static_cast<size_t>(msg.raw_size) != 3 * n) {
    *error = "raw_size " + std::to_string(msg.raw_size) + " is not 3 bytes for each of the " +
             std::to_string(n) + " cells";
    return false;
  }
  if (msg.num_bytes < 0 || static_cast<size_t>(msg.num_bytes) != msg.data.size()) {
    *error = "num_bytes disagrees with the data";
    return false;
  }
  std::vector<uint8_t> inflated;
  const std::vector<uint8_t>* raw = &msg.data;
  if (msg.encoding == local_grid_t::ENCODING_ZLIB) {
    inflated.resize(3 * n);
    uLongf length = static_cast<uLongf>(inflated.size());
    const int rc = uncompress(inflated.data(), &length, msg.data.data(),
                              static_cast<uLong>(msg.data.size()));
    if (rc != Z_OK || length != inflated.size()) {
      *error = rc == Z_BUF_ERROR ? "the data inflates to more than raw_size bytes"
                                 : "the data is not a zlib stream of raw_size bytes";
      return false;
    }
    raw = &inflated;
  } else if (msg.encoding != local_grid_t::ENCODING_RAW) {
    *error = "unknown encoding " + std::to_string(static_cast<int>(msg.encoding));
    return false;
  } else if (msg.data.size() != 3 * n) {
    *error = "the raw data is not raw_size bytes";
    return false;
  }
  LocalGridSample sample;
  sample.utime = msg.utime;
  sample.map_epoch = msg.map_epoch;
  sample.pose_utime = msg.pose_utime;
  sample.max_distance_m = msg.max_distance_m;
  LocalGrid& g = sample.grid;
  g.origin = Eigen::Vector3d(msg.origin[0], msg.origin[1], msg.origin[2]);
  g.resolution = msg.resolution;
  g.size = Eigen::Vector3i(msg.size[0], msg.size[1], msg.size[2]);
  g.state.resize(n);
  g.distance.resize(n);
  for (size_t c = 0; c < n; ++c) {
    const int8_t s = static_cast<int8_t>((*raw)[c]);
    const int16_t mm = static_cast<int16_t>(static_cast<uint16_t>((*raw)[n + 2 * c]) |
                                            static_cast<uint16_t>((*raw)[n + 2 * c + 1]) << 8);
    if (s != local_grid_t::UNKNOWN && s != local_grid_t::FREE && s != local_grid_t::OCCUPIED) {
      *error = "cell " + std::to_string(c) + " has state " + std::to_string(s);
      return false;
    }
    g.state[c] = static_cast<VoxelState>(s);
    g.distance[c] = g.state[c] == VoxelState::kUnknown || mm == kUnknownMm
                        ? std::numeric_limits<float>::quiet_NaN()
                        : static_cast<float>(mm) * 0.001f;
  }
  *out = std::move(sample);
  return true;
}

}  // namespace cblox
