#include "daemon/common/local_grid_codec.h"

#include <zlib.h>

#include <cmath>
#include <limits>
#include <string>
#include <vector>

#include <gtest/gtest.h>

namespace cblox {
namespace {

/// A 5 x 3 x 2 grid: unknown, free and occupied cells, distances with sub-mm parts.
LocalGridSample sample() {
  LocalGridSample s;
  s.utime = 11;
  s.map_epoch = 22;
  s.pose_utime = 33;
  s.max_distance_m = 2.0f;
  LocalGrid& g = s.grid;
  g.origin = Eigen::Vector3d(-1.25, 0.5, 0.0);
  g.resolution = 0.1;
  g.size = Eigen::Vector3i(5, 3, 2);
  for (int c = 0; c < 30; ++c) {
    const VoxelState state = c % 3 == 0 ? VoxelState::kUnknown
                             : c % 3 == 1 ? VoxelState::kFree
                                          : VoxelState::kOccupied;
    g.state.push_back(state);
    g.distance.push_back(state == VoxelState::kUnknown ? std::numeric_limits<float>::quiet_NaN()
                         : state == VoxelState::kFree  ? 0.0374f * static_cast<float>(c)
                                                       : -0.0121f * static_cast<float>(c));
  }
  return s;
}

TEST(LocalGridCodecTest, RoundTripsToTheMillimetre) {
  const LocalGridSample in = sample();
  for (const int level : {0, 1, 9}) {
    const local_grid_t msg = encodeLocalGrid(in, level);
    EXPECT_EQ(msg.encoding, level == 0 ? local_grid_t::ENCODING_RAW : local_grid_t::ENCODING_ZLIB);
    EXPECT_EQ(msg.raw_size, 90);
    EXPECT_EQ(msg.num_bytes, static_cast<int32_t>(msg.data.size()));
    LocalGridSample out;
    std::string error;
    ASSERT_TRUE(decodeLocalGrid(msg, &out, &error)) << error;
    EXPECT_EQ(out.utime, 11);
    EXPECT_EQ(out.map_epoch, 22);
    EXPECT_EQ(out.pose_utime, 33);
    EXPECT_EQ(out.max_distance_m, 2.0f);
    EXPECT_EQ(out.grid.origin, in.grid.origin);
    EXPECT_EQ(out.grid.resolution, 0.1);
    EXPECT_EQ(out.grid.size, in.grid.size);
    ASSERT_EQ(out.grid.state, in.grid.state);
    for (size_t c = 0; c < 30; ++c) {
      if (in.grid.state[c] == VoxelState::kUnknown) {
        EXPECT_TRUE(std::isnan(out.grid.distance[c]));
      } else {
        EXPECT_NEAR(out.grid.distance[c], in.grid.distance[c], 0.0005f);
      }
    }
  }
}

TEST(LocalGridCodecTest, ThePayloadIsStatesThenLittleEndianMillimetres) {
  LocalGridSample s = sample();
  s.grid.size = Eigen::Vector3i(2, 1, 1);
  s.grid.state = {VoxelState::kFree, VoxelState::kOccupied};
  s.grid.distance = {1.2345f, -40.0f};  // the second clamps to -32.767 m
  const local_grid_t msg = encodeLocalGrid(s, 0);
  // 1235 = 0x04D3, -32767 = 0x8001.
  EXPECT_EQ(msg.data, (std::vector<uint8_t>{1, 2, 0xD3, 0x04, 0x01, 0x80}));
}

TEST(LocalGridCodecTest, RefusesForgedMessagesBeforeAllocatingByThem) {
  const local_grid_t good = encodeLocalGrid(sample(), 1);
  std::string error;
  LocalGridSample out;
  const auto refused = [&](local_grid_t msg, const std::string& why) {
    error.clear();
    EXPECT_FALSE(decodeLocalGrid(msg, &out, &error)) << why;
    EXPECT_NE(error.find(why), std::string::npos) << error;
  };
  local_grid_t m = good;
  m.size[1] = 0;
  refused(m, "size[1]");
  m = good;
  m.size[0] = m.size[1] = m.size[2] = 1 << 30;  // 2^90 cells
  refused(m, "cells");
  m = good;
  m.raw_size = 91;
  refused(m, "raw_size");
  m = good;
  m.resolution = std::nan("");
  refused(m, "resolution");
  m = good;
  m.origin[2] = std::numeric_limits<double>::infinity();
  refused(m, "origin");
  m = good;
  m.encoding = 7;
  refused(m, "encoding");
  m = good;
  m.data.resize(m.data.size() / 2);
  m.num_bytes = static_cast<int32_t>(m.data.size());
  refused(m, "zlib");
  m = good;
  m.num_bytes = 3;
  refused(m, "num_bytes");
  // A stream that inflates to more than raw_size (a zip bomb) stops at raw_size.
  std::vector<uint8_t> big(1 << 20, 0);
  uLongf packed = compressBound(big.size());
  m = good;
  m.data.resize(packed);
  ASSERT_EQ(compress2(m.data.data(), &packed, big.data(), big.size(), 9), Z_OK);
  m.data.resize(packed);
  m.num_bytes = static_cast<int32_t>(packed);
  refused(m, "more than raw_size");
  // A state outside the three.
  local_grid_t raw = encodeLocalGrid(sample(), 0);
  raw.data[4] = 9;
  refused(raw, "state 9");
  // Refusals leave *out as it was.
  out.map_epoch = 5;
  EXPECT_FALSE(decodeLocalGrid(raw, &out, &error));
  EXPECT_EQ(out.map_epoch, 5);
}

TEST(LocalGridCodecTest, EncodingRefusesInconsistentGrids) {
  LocalGridSample s = sample();
  s.grid.state.pop_back();
  EXPECT_THROW(encodeLocalGrid(s), std::invalid_argument);
  EXPECT_THROW(encodeLocalGrid(sample(), 10), std::invalid_argument);
}

}  // namespace
}  // namespace cblox
