#pragma once

// Pairs the frames of two free-running or hardware-triggered cameras by timestamp.

#include <cstddef>
#include <cstdint>
#include <deque>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

namespace cblox {

enum class StereoSide { kLeft, kRight };

/// Options of StereoPairer. Plain value type.
struct StereoPairerOptions {
  /// Largest |t_right - t_left| of a pair (ns, > 0).
  int64_t tolerance_ns = 5'000'000;
  /// A frame waits for its partner at most this long, measured in timestamps behind the
  /// newest frame of either stream (ns, >= tolerance_ns): it bounds the wait when the other
  /// stream is silent.
  int64_t max_wait_ns = 200'000'000;
  /// Most frames waiting per side (>= 1); beyond it the oldest is dropped.
  size_t max_queue = 8;

  /// Empty if usable, else a message naming the first bad field. Thread-safe (pure).
  std::string validate() const;
};

/// A left and a right frame of (nearly) the same instant.
struct StereoPair {
  uint64_t left_id = 0;
  uint64_t right_id = 0;
  int64_t left_ns = 0;
  int64_t right_ns = 0;
};

/// Why a frame left the pairer without a partner.
enum class StereoDropReason {
  kUnpaired,    ///< the other stream moved past it with no frame within the tolerance
  kExpired,     ///< waited max_wait_ns while the other stream delivered nothing to pair
  kOverflow,    ///< its side's queue was full (it was the oldest)
  kOutOfOrder,  ///< not newer than a frame already paired or dropped on its side
  kFlushed,     ///< removed by clear()
};

/// "unpaired", "expired", "overflow", "out_of_order", "flushed". Thread-safe (pure).
std::string_view stereoDropReasonName(StereoDropReason reason);

struct StereoDrop {
  StereoSide side = StereoSide::kLeft;
  uint64_t id = 0;
  int64_t timestamp_ns = 0;
  StereoDropReason reason = StereoDropReason::kUnpaired;
};

/// Counters of a StereoPairer. Plain value type.
struct StereoPairerStats {
  int64_t pairs = 0;
  /// Frames dropped without a partner (kUnpaired, kExpired or kOverflow), per side.
  int64_t left_unpaired = 0;
  int64_t right_unpaired = 0;
  /// Of the unpaired frames, those whose nearest frame on the other stream was beyond the
  /// tolerance but within half that stream's frame interval: the streams are out of step
  /// (drifted apart), rather than the other camera having lost that frame.
  int64_t drift = 0;
  int64_t overflow = 0;       ///< kOverflow drops (also in *_unpaired)
  int64_t out_of_order = 0;   ///< kOutOfOrder drops (not in *_unpaired)
  int64_t last_dt_ns = 0;     ///< t_right - t_left of the latest pair
  int64_t max_abs_dt_ns = 0;  ///< largest |t_right - t_left| of any pair
};

/// Pairs left and right frames, which arrive separately, each with a timestamp and an id
/// the caller uses to find its image. Frames on each side must come roughly in timestamp
/// order (they are sorted within the waiting queue; one older than a frame already paired or
/// dropped on its side is dropped as kOutOfOrder). Whenever both sides have frames waiting
/// the oldest ones are decided for good:
///   |t_r - t_l| <= tolerance  -> paired, unless the next frame of either side is nearer to
///                                the other (then the farther one is dropped, kUnpaired);
///   t_r - t_l > tolerance     -> the left frame can have no partner: dropped (kUnpaired);
///   t_l - t_r > tolerance     -> likewise the right frame.
/// So each pair is the nearest-timestamp match within the tolerance. Frames more than
/// max_wait_ns behind the newest frame (kExpired) or beyond max_queue (kOverflow) are
/// dropped while the other side is silent. Not thread-safe: one thread uses it.
class StereoPairer {
 public:
  /// `options` must be valid (validate() empty); throws std::invalid_argument otherwise.
  explicit StereoPairer(const StereoPairerOptions& options);

  /// Adds a frame of `side` and appends the pairs completed and frames dropped (in the order
  /// decided) to *pairs and *drops (both non-null).
  void push(StereoSide side, int64_t timestamp_ns, uint64_t id, std::vector<StereoPair>* pairs,
            std::vector<StereoDrop>* drops);

  /// Drops every waiting frame (kFlushed, not counted as unpaired, appended to *drops,
  /// non-null) and forgets the streams' history, e.g. after the cameras were reopened.
  void clear(std::vector<StereoDrop>* drops);

  /// Frames waiting on `side`.
  size_t waiting(StereoSide side) const;

  const StereoPairerStats& stats() const { return stats_; }
  const StereoPairerOptions& options() const { return options_; }

 private:
  struct Entry {
    int64_t timestamp_ns;
    uint64_t id;
  };
  struct Stream {
    std::deque<Entry> queue;                  // sorted by timestamp
    std::optional<int64_t> last_consumed_ns;  // the newest frame paired or dropped
    std::optional<int64_t> interval_ns;       // between the last two consumed frames
  };

  Stream& stream(StereoSide side) { return side == StereoSide::kLeft ? left_ : right_; }
  void consume(StereoSide side, int64_t timestamp_ns);
  void drop(StereoSide side, StereoDropReason reason, std::vector<StereoDrop>* drops);
  bool isDrift(StereoSide side, int64_t timestamp_ns) const;
  void match(std::vector<StereoPair>* pairs, std::vector<StereoDrop>* drops);

  StereoPairerOptions options_;
  Stream left_;
  Stream right_;
  std::optional<int64_t> newest_ns_;
  StereoPairerStats stats_;
};

}  // namespace cblox
