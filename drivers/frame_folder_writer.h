#pragma once

#include <cstddef>
#include <string>

#include "core/io/tum_trajectory.h"
#include "drivers/frame_source.h"

namespace cblox {

/// Writes the frames of any source to a folder a person can look at and that
/// TumRgbdReader reads back (TUM RGB-D layout, extended with the stereo pair):
///   rgb/<t>.png, depth/<t>.png     colour and 16-bit depth (depth_scale metres per unit,
///                                  5000 units per metre by default, as TUM)
///   left/<t>.png, right/<t>.png    rectified grey stereo pair
///   rgb.txt depth.txt left.txt right.txt   "<t> <file>" lists (t in seconds, 6 decimals)
///   groundtruth.txt                TUM trajectory of the primary camera C
///   camera-intrinsics.txt          3x3 K of the depth camera
///   stereo.yaml                    rectified stereo intrinsics and baseline
///   source.txt                     the source's name and notes
/// Depth beyond the 16-bit range (65535 * depth_scale) is written as 0 (invalid) and counted.
/// Thread-safety: not thread-safe.
class FrameFolderWriter {
 public:
  /// Creates the folder (and parents) and writes the calibration files. Returns false with a
  /// message naming the path when it cannot. `depth_units_per_metre` must be > 0.
  bool open(const std::string& folder, const SourceInfo& info, std::string* error,
            double depth_units_per_metre = 5000.0);

  /// Writes one frame's images and list entries. False with a message on I/O errors.
  bool write(const CaptureFrame& frame, std::string* error);

  /// Writes groundtruth.txt and source.txt and closes the lists. False on I/O errors.
  bool close(std::string* error);

  size_t framesWritten() const { return frames_; }
  size_t depthPixelsOutOfRange() const { return out_of_range_; }

 private:
  std::string folder_;
  SourceInfo info_;
  double units_per_metre_ = 5000.0;
  std::string rgb_list_, depth_list_, left_list_, right_list_;
  StampedTrajectory ground_truth_;
  size_t frames_ = 0;
  size_t out_of_range_ = 0;
};

}  // namespace cblox
