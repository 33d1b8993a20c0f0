#pragma once

#include <atomic>
#include <cstdint>
#include <deque>
#include <mutex>
#include <string>

#include "core/optimization/disparity_offset.h"

namespace cblox {

/// Settings of the online estimate of the stereo rig's disparity offset (a right principal
/// point off the calibration's: see estimateDisparityOffset). Plain value type.
struct DisparityCorrectionConfig {
  /// Estimate the offset in local mapping and correct new frames' disparities by it (stereo
  /// only; an RGB-D frame's virtual disparities are never corrected).
  bool enabled = true;
  /// An estimate from the local BA window of every this many keyframes, >= 1, and once the
  /// correction is settled (settled()) of every settled_every_keyframes: a calibration
  /// drifts slowly, and a solve costs about as much as the local BA itself.
  int every_keyframes = 1;
  int settled_every_keyframes = 10;
  /// The correction is the median of the last `window` estimates, once there are at least
  /// `min_estimates` of them and their spread (1.4826 x the median absolute deviation) is at
  /// most max_spread_px; until then it keeps its last value (0 at the start).
  /// 1 <= min_estimates <= window.
  int window = 9;
  int min_estimates = 5;
  double max_spread_px = 0.3;  ///< > 0
  double settled_tolerance_px = 0.1;  ///< > 0, see DisparityCorrection::settled()
  /// A median within this of 0 sets the correction to 0, >= 0: a calibration good to the
  /// sub-pixel stereo matcher's own accuracy (about 0.1 px on exact images, with a bias of a
  /// few hundredths that depends on the texture) is left alone rather than chased.
  double min_correction_px = 0.1;
  /// Estimates farther than this from 0 are refused as implausible (a failed solve, not a
  /// calibration), > 0.
  double max_abs_px = 5.0;
  DisparityOffsetSolverConfig solver;

  /// Empty when valid, else a message naming the first bad field. Thread-safe.
  std::string validate() const;
};

/// Statistics of a DisparityCorrection. Plain value type.
struct DisparityCorrectionStats {
  uint64_t estimates = 0;        ///< accepted into the window
  uint64_t refused = 0;          ///< beyond max_abs_px
  uint64_t updates = 0;          ///< times the correction was set from the window
  double correction_px = 0.0;    ///< in use
  double last_estimate_px = 0.0;
  double spread_px = 0.0;        ///< of the window at the last estimate
};

/// The disparity correction in use: the robust combination of per-window estimates of the
/// disparity offset c (estimateDisparityOffset on raw measurements). New frames' right
/// columns are corrected by it (u_right - c, so disparities grow by c). Thread-safe: the
/// local mapping thread adds estimates, the tracking thread reads correctionPx().
class DisparityCorrection {
 public:
  /// Throws std::invalid_argument with validate()'s message.
  explicit DisparityCorrection(const DisparityCorrectionConfig& config);

  /// Adds one window's estimate (pixels) and updates the correction as configured.
  void addEstimate(double offset_px);
  /// The correction in use, pixels (0 until the window settles; always 0 when disabled).
  float correctionPx() const { return correction_px_.load(std::memory_order_relaxed); }
  /// True once the window holds `window` estimates, the last one left the correction set
  /// from it (spread within max_spread_px) and lay within settled_tolerance_px of it: a
  /// window whose estimates still trend (a map whose first keyframes hold a wrong scale) is
  /// not settled.
  bool settled() const;
  /// The configured interval between estimates, in keyframes: every_keyframes, or
  /// settled_every_keyframes once settled().
  int estimateInterval() const;
  DisparityCorrectionStats stats() const;
  const DisparityCorrectionConfig& config() const { return config_; }

 private:
  DisparityCorrectionConfig config_;
  std::atomic<float> correction_px_{0.0f};
  mutable std::mutex mutex_;
  std::deque<double> recent_;
  bool settled_ = false;
  DisparityCorrectionStats stats_;
};

}  // namespace cblox
