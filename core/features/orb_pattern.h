#pragma once

#include <array>
#include <cstdint>

namespace cblox {

/// Number of point pairs (= descriptor bits) of ORB's rotated BRIEF pattern.
inline constexpr int kOrbPatternPairs = 256;

/// One intensity test of rotated BRIEF: bit = I(a) < I(b), with a and b offsets (x right,
/// y down, pixels) from the keypoint, in the keypoint's rotated frame. Values in [-13, 12].
struct OrbPointPair {
  struct Point {
    int8_t x, y;
  };
  Point a, b;
};

/// OpenCV's (and ORB-SLAM2's) learned 31x31 ORB pattern, bit i = pair i (see orb_pattern.cc
/// for its origin and licence). A constant table; thread-safe.
const std::array<OrbPointPair, kOrbPatternPairs>& orbPattern31();

}  // namespace cblox
