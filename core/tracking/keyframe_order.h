#pragma once

#include <cstdint>

namespace cblox {

class Keyframe;

/// Keyframe identifier: 0, 1, 2, ... in creation order (the same type as in
/// core/submap/submap.h and core/vocabulary/keyframe_database.h).
using KeyframeId = int64_t;

/// Orders keyframes by id (not by address), so that every walk over a set or map of
/// keyframes is the same from run to run. Thread-safe (ids are immutable).
struct KeyframeIdLess {
  bool operator()(const Keyframe* a, const Keyframe* b) const;
};

}  // namespace cblox
