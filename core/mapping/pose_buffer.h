#pragma once

#include <cstddef>
#include <cstdint>
#include <deque>
#include <mutex>
#include <optional>
#include <string>

#include "core/geometry/se3.h"

namespace cblox {

/// One tracked (or ground-truth) camera pose with the tracker's state.
struct TimedPose {
  int64_t utime = 0;  ///< capture time of the frame, microseconds
  Transformationd T_G_C;
  bool tracking_ok = true;  ///< false for LOST / NOT_INITIALIZED: the pose is meaningless
  bool jump = false;        ///< discontinuity before this pose (relocalisation, loop, reset)
  int32_t epoch = 0;        ///< tracker map epoch; poses of different epochs are unrelated
  /// The keyframe (mapper key, map_epoch_key.h) the frame was tracked against, -1: none.
  int64_t reference_keyframe = -1;
};

/// Recent frame poses, looked up at a depth frame's time stamp by geodesic interpolation
/// between the two poses around it. Never interpolates across a tracking jump, a lost pose
/// or an epoch change, nor over a gap longer than max_gap_s.
///
/// Thread-safety: every member function is thread-safe (one internal mutex): the LCM thread
/// adds poses while the integrator thread looks them up.
class PoseBuffer {
 public:
  struct Config {
    double max_gap_s = 0.25;  ///< longest interval between the two poses interpolated
    size_t capacity = 1024;   ///< oldest poses are forgotten beyond this
    std::string validate() const;
  };

  enum class AddResult { kAdded, kDuplicate, kOutOfOrder, kInvalid };
  enum class Lookup {
    kFound,       ///< *T_G_C set (exact or interpolated)
    kNotYet,      ///< newer than every pose: may be answered when more poses arrive
    kTooOld,      ///< older than every pose kept
    kGap,         ///< the poses around it are more than max_gap_s apart
    kAcrossJump,  ///< a tracking jump or epoch change lies between the poses around it
    kLost,        ///< a pose around it is not tracked (LOST / NOT_INITIALIZED)
  };

  /// Throws std::invalid_argument with Config::validate()'s message.
  explicit PoseBuffer(const Config& config);

  /// Adds a pose. Time stamps must increase: an equal one is kDuplicate, an older one
  /// kOutOfOrder; a non-finite pose or a quaternion far from unit norm is kInvalid. Nothing
  /// is stored unless kAdded.
  AddResult add(const TimedPose& pose);

  /// Pose at `utime`. On kFound, *T_G_C is the pose and *jump tells whether the frame is the
  /// first after a discontinuity (it has the jump pose itself); `reference_keyframe`, when
  /// given, is set to the reference keyframe of the pose at `utime`, or of the nearer of the
  /// two poses interpolated (the later one at the midpoint).
  Lookup lookup(int64_t utime, Transformationd* T_G_C, bool* jump,
                int64_t* reference_keyframe = nullptr) const;

  /// Holds the buffer's lock for its lifetime so that several lookups see one state: a pose
  /// added between two lookups of a scan over waiting frames would otherwise make a newer
  /// frame "not yet" and an older one "too old" in the same scan. Keep it short-lived; do not
  /// call the buffer's own member functions while holding it.
  class Reader {
   public:
    explicit Reader(const PoseBuffer& buffer) : buffer_(buffer), lock_(buffer.mutex_) {}
    Lookup lookup(int64_t utime, Transformationd* T_G_C, bool* jump,
                  int64_t* reference_keyframe = nullptr) const {
      return buffer_.lookupLocked(utime, T_G_C, jump, reference_keyframe);
    }

   private:
    const PoseBuffer& buffer_;
    std::unique_lock<std::mutex> lock_;
  };

  size_t size() const;
  /// Time stamp of the newest pose, or INT64_MIN when empty.
  int64_t newestUtime() const;
  /// The newest pose that is tracked (tracking_ok), or nullopt when there is none.
  std::optional<TimedPose> newestTracked() const;
  void clear();

  static const char* name(Lookup result);

 private:
  Lookup lookupLocked(int64_t utime, Transformationd* T_G_C, bool* jump,
                      int64_t* reference_keyframe) const;

  Config config_;
  mutable std::mutex mutex_;
  std::deque<TimedPose> poses_;
};

}  // namespace cblox
