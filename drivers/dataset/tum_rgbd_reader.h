#pragma once

#include <cstddef>
#include <optional>
#include <string>
#include <vector>

#include "core/geometry/image.h"
#include "core/geometry/pinhole_camera.h"
#include "core/geometry/se3.h"

namespace cblox {

/// One frame of a TUM RGB-D sequence, driven by the depth stream.
struct TumRgbdFrame {
  double timestamp_s = 0.0;  // depth image timestamp (seconds, as in depth.txt)
  /// Timestamp of the associated colour image (seconds), std::nullopt if none.
  std::optional<double> color_timestamp_s;
  DepthImage depth;  // metres; 0 = invalid (stored as 0)
  ColorImage color;  // RGB; empty when no colour image is associated
  /// Camera-to-world pose interpolated from groundtruth.txt at timestamp_s, std::nullopt when
  /// there is no ground truth at that time.
  std::optional<Transformationd> T_G_C;
};

/// Reads a folder in the TUM RGB-D benchmark layout:
///   rgb.txt, depth.txt         "timestamp filename" lines (seconds, path relative to the
///                              folder), '#' comments
///   rgb/*.png                  8-bit colour
///   depth/*.png                16-bit single-channel depth, depth_scale metres per unit
///   groundtruth.txt            optional: TUM trajectory "t tx ty tz qx qy qz qw"
///   camera-intrinsics.txt      optional: 3x3 K (not part of TUM; see Options::intrinsics)
/// Each depth image is one frame. It is associated with the colour image nearest in time
/// within Options::max_association_difference_s, as TUM's associate.py does (greedily by
/// smallest difference, each colour image used at most once); a depth image without one is
/// still played, without colour. Immutable after open(): all member functions are thread-safe.
class TumRgbdReader {
 public:
  /// Reader options; the defaults are the TUM RGB-D benchmark's.
  struct Options {
    /// Metres per depth unit (> 0); TUM stores 5000 units per metre.
    double depth_scale = 1.0 / 5000.0;
    /// Largest |t_depth - t_rgb| (seconds, > 0) for an association, as associate.py's
    /// --max_difference (a pair is associated when the difference is strictly smaller).
    double max_association_difference_s = 0.02;
    /// Ground truth is interpolated between two poses at most this far apart (seconds, > 0).
    double groundtruth_max_gap_s = 0.1;
    /// Depth camera intrinsics. If unset, camera-intrinsics.txt in the folder is read, else
    /// TUM's documented default for uncalibrated use (fx = fy = 525, cx = 319.5, cy = 239.5) is
    /// used. width and height of 0 are taken from the first depth image.
    std::optional<PinholeIntrinsics> intrinsics;

    /// Returns an empty string if the options are usable, else a message naming the first bad
    /// field. Thread-safe (pure).
    std::string validate() const;
  };

  /// Opens `folder`: reads rgb.txt and depth.txt, drops entries whose image is missing on
  /// disk (listed in skipped()), associates colour with depth, reads the ground truth if
  /// present and determines the intrinsics (image size from the first depth image). Returns
  /// std::nullopt and, if error is non-null, a message naming the offending file (and line
  /// where there is one) when the options are invalid; the folder is unreadable; rgb.txt or
  /// depth.txt is missing, has a malformed line (not "timestamp filename", timestamp not a
  /// finite number) or timestamps that do not strictly increase; no depth image remains;
  /// groundtruth.txt is malformed (see readTumTrajectory()); camera-intrinsics.txt is not a
  /// valid K; the intrinsics are invalid; or the first depth image is unreadable or not
  /// 16-bit single-channel. Thread-safe.
  static std::optional<TumRgbdReader> open(const std::string& folder, const Options& options,
                                           std::string* error);

  /// Number of frames (depth images found on disk). Thread-safe.
  size_t size() const { return frames_.size(); }

  /// Depth timestamp (seconds) of the i-th frame; i < size(). Thread-safe.
  double timestamp(size_t i) const { return frames_.at(i).timestamp_s; }

  /// Depth camera intrinsics (see Options::intrinsics). Thread-safe.
  const PinholeIntrinsics& intrinsics() const { return intrinsics_; }

  /// True if groundtruth.txt was found and read. Thread-safe.
  bool hasGroundTruth() const { return has_groundtruth_; }

  /// Metres per unit of the 16-bit depth images. Thread-safe.
  double depthScale() const { return depth_scale_; }

  /// One human-readable line per image entry open() dropped (missing on disk) and per depth
  /// frame played without colour. Thread-safe.
  const std::vector<std::string>& skipped() const { return skipped_; }

  /// Human-readable remarks: default intrinsics in use, absent ground truth, number of frames
  /// without colour or ground truth, unused colour images. Thread-safe.
  const std::vector<std::string>& notes() const { return notes_; }

  /// The folder this reader was opened on. Thread-safe.
  const std::string& folder() const { return folder_; }

  /// Reads the i-th frame into *frame (non-null). Returns false, leaving *frame untouched and
  /// writing a message naming the file to *error (if non-null), when i is out of range; the
  /// depth image is missing, unreadable, not 16-bit single-channel or not the intrinsics'
  /// size; or the colour image is missing, unreadable or not the depth image's size.
  /// Thread-safe.
  bool read(size_t i, TumRgbdFrame* frame, std::string* error) const;

 private:
  struct FrameFiles {
    double timestamp_s = 0.0;
    std::string depth_path;
    std::optional<double> color_timestamp_s;
    std::string color_path;  // empty: no colour
    std::optional<Transformationd> T_G_C;
  };

  TumRgbdReader() = default;

  std::string folder_;
  double depth_scale_ = 0.0;
  PinholeIntrinsics intrinsics_;
  std::vector<FrameFiles> frames_;
  bool has_groundtruth_ = false;
  std::vector<std::string> skipped_;
  std::vector<std::string> notes_;
};

}  // namespace cblox
