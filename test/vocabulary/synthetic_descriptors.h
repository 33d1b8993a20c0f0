#pragma once

#include <cstdint>
#include <random>
#include <vector>

#include "core/features/orb_descriptor.h"

namespace cblox::test {

/// A uniformly random 256-bit descriptor.
inline OrbDescriptor randomDescriptor(std::mt19937_64& rng) {
  OrbDescriptor d;
  for (uint64_t& w : d.words) w = rng();
  return d;
}

/// `centre` with exactly `flips` distinct random bits flipped.
inline OrbDescriptor flipBits(const OrbDescriptor& centre, int flips, std::mt19937_64& rng) {
  OrbDescriptor d = centre;
  std::vector<int> bits(256);
  for (int i = 0; i < 256; ++i) bits[static_cast<size_t>(i)] = i;
  for (int i = 0; i < flips; ++i) {
    const auto j =
        static_cast<size_t>(i) + static_cast<size_t>(rng() % (256 - static_cast<uint64_t>(i)));
    std::swap(bits[static_cast<size_t>(i)], bits[j]);
    d.setBit(bits[static_cast<size_t>(i)], !d.bit(bits[static_cast<size_t>(i)]));
  }
  return d;
}

/// Clustered data: `centres` random centres, `members` descriptors per centre with `flips`
/// flipped bits each; members[c * members_per_centre + m] belongs to centre c.
struct ClusteredData {
  std::vector<OrbDescriptor> centres;
  std::vector<OrbDescriptor> members;
  std::vector<int> centre_of;
};

inline ClusteredData makeClusteredData(int centres, int members_per_centre, int flips,
                                       uint64_t seed) {
  std::mt19937_64 rng(seed);
  ClusteredData data;
  for (int c = 0; c < centres; ++c) data.centres.push_back(randomDescriptor(rng));
  for (int c = 0; c < centres; ++c) {
    for (int m = 0; m < members_per_centre; ++m) {
      data.members.push_back(flipBits(data.centres[static_cast<size_t>(c)], flips, rng));
      data.centre_of.push_back(c);
    }
  }
  return data;
}

}  // namespace cblox::test
