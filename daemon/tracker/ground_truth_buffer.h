#pragma once

#include <chrono>
#include <condition_variable>
#include <cstddef>
#include <cstdint>
#include <deque>
#include <mutex>
#include <optional>

#include "core/geometry/se3.h"

namespace cblox {

/// The last few ground-truth poses (CBLOX_GT_POSE) by frame, for starting the tracker's map
/// at the ground-truth pose of its first keyframe (so the tracker's frame G is the
/// simulator's or dataset's). The LCM thread adds poses; the tracking thread waits for the
/// pose of the frame it is about to initialise with.
///
/// Thread-safety: all member functions are thread-safe (one mutex and condition variable).
class GroundTruthBuffer {
 public:
  /// Keeps at most `capacity` poses (the oldest is dropped), >= 1.
  explicit GroundTruthBuffer(size_t capacity = 64) : capacity_(capacity < 1 ? 1 : capacity) {}

  /// Adds the pose T_G_C of a frame (frame_id < 0: matched by utime alone) and wakes waiters.
  /// A pose older than the newest one kept means the source restarted: the kept ones go.
  void add(int64_t frame_id, int64_t utime, const Transformationd& T_G_C);

  /// The pose of the frame (same frame_id, or same utime for poses added without a frame id),
  /// waiting up to `timeout` for it to arrive; std::nullopt when it did not, or when
  /// interrupt() was called.
  std::optional<Transformationd> waitFor(int64_t frame_id, int64_t utime,
                                         std::chrono::milliseconds timeout);

  /// Makes current and future waitFor() calls return at once (shutdown).
  void interrupt();

 private:
  struct Entry {
    int64_t frame_id = -1;
    int64_t utime = 0;
    Transformationd T_G_C;
  };
  std::optional<Transformationd> find(int64_t frame_id, int64_t utime) const;

  const size_t capacity_;
  std::mutex mutex_;
  std::condition_variable added_;
  std::deque<Entry> entries_;
  bool interrupted_ = false;
};

}  // namespace cblox
