#pragma once

#include <array>
#include <bit>
#include <cstdint>
#include <cstring>

namespace cblox {

/// A 256-bit rotated-BRIEF (ORB) descriptor, stored as four 64-bit words so that the Hamming
/// distance is four popcounts. Bit i of the descriptor is bit (i % 64) of words[i / 64]; the
/// byte layout equals OpenCV's 32-byte ORB row on little-endian machines (fromBytes/toBytes).
/// Value type; thread-safe.
struct OrbDescriptor {
  std::array<uint64_t, 4> words{};

  /// From 32 bytes (one row of an OpenCV CV_8U ORB descriptor matrix).
  static OrbDescriptor fromBytes(const uint8_t* bytes) {
    OrbDescriptor d;
    std::memcpy(d.words.data(), bytes, 32);
    return d;
  }
  /// Writes the 32 bytes of the descriptor.
  void toBytes(uint8_t* bytes) const { std::memcpy(bytes, words.data(), 32); }

  /// Bit i in [0, 256).
  bool bit(int i) const { return (words[static_cast<size_t>(i) >> 6] >> (i & 63)) & 1u; }
  void setBit(int i, bool value) {
    const uint64_t mask = uint64_t{1} << (i & 63);
    uint64_t& w = words[static_cast<size_t>(i) >> 6];
    w = value ? (w | mask) : (w & ~mask);
  }

  bool operator==(const OrbDescriptor&) const = default;
};

/// Number of differing bits, in [0, 256]. Thread-safe (pure).
inline int hammingDistance(const OrbDescriptor& a, const OrbDescriptor& b) {
  return std::popcount(a.words[0] ^ b.words[0]) + std::popcount(a.words[1] ^ b.words[1]) +
         std::popcount(a.words[2] ^ b.words[2]) + std::popcount(a.words[3] ^ b.words[3]);
}

}  // namespace cblox
