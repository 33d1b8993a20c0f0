#pragma once

#include <cstddef>

namespace cblox {

class Keyframe;

/// Where the tracker hands new keyframes: the local mapping thread (ORB-SLAM2's
/// LocalMapping::InsertKeyFrame / AcceptKeyFrames / InterruptBA). All methods are called from
/// the tracking thread and must be thread-safe.
class KeyframeSink {
 public:
  virtual ~KeyframeSink() = default;
  /// True when local mapping is idle and would take a keyframe now.
  virtual bool acceptsKeyframes() const = 0;
  /// Keyframes waiting to be processed.
  virtual size_t queuedKeyframes() const = 0;
  /// Queues a keyframe that the tracker has already added to the map.
  virtual void insertKeyframe(Keyframe* keyframe) = 0;
  /// Asks a running local bundle adjustment to stop early (a keyframe is urgent).
  virtual void interruptBundleAdjustment() = 0;
};

}  // namespace cblox
