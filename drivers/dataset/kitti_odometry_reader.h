#pragma once

#include <cstddef>
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "core/geometry/image.h"
#include "core/geometry/se3.h"
#include "core/geometry/stereo_rig.h"

namespace cblox {

/// One stereo pair of a KITTI odometry sequence (already rectified by KITTI).
struct KittiStereoFrame {
  int64_t timestamp_ns = 0;  // times.txt's seconds, in nanoseconds (the sequence's clock)
  GrayImage left;            // image_0 (camera 0), calibration().intrinsics
  GrayImage right;           // image_1 (camera 1), same intrinsics, +baseline_m along x
  /// Camera 0 in the ground-truth world frame (the sequence's first camera 0 pose), or
  /// std::nullopt without ground truth.
  std::optional<Transformationd> T_G_L;
};

/// Reads a grey stereo sequence in the layout of the KITTI odometry benchmark:
///   image_0/NNNNNN.png, image_1/NNNNNN.png   8-bit grey, rectified; numbered from 000000
///                                             without gaps, the same numbers in both
///   calib.txt                                 "P0: " and "P1: " rows of 12 numbers (3x4
///                                             row-major projection matrices); P2, P3 (the
///                                             colour cameras) and Tr (Velodyne to camera 0)
///                                             are read and not used (notes() says so)
///   times.txt                                 one time per pair, seconds, increasing
///   poses.txt, or ../../poses/<folder name>.txt   optional ground truth: one row of 12
///                                             numbers per pair, camera 0 to world, 3x4
///                                             row-major (KITTI's dataset/poses/NN.txt)
/// The intrinsics are P0's (fx, fy, cx, cy; the image size from the first left image); the
/// baseline is -P1[0][3] / fx (KITTI's P1 = K [I | (-b, 0, 0)]). Immutable after open(): all
/// member functions are thread-safe.
class KittiOdometryReader {
 public:
  /// Opens the sequence folder. Returns std::nullopt and, if error is non-null, a message
  /// naming the file (and its line where there is one) when: the folder, image_0/, image_1/,
  /// calib.txt or times.txt is missing; a calib.txt line has no "LABEL:" or a P row is not 12
  /// finite numbers, P0 or P1 is missing, P0 is not K [I | 0] (a skew, a last row other than
  /// 0 0 1 0, a translation), P1's intrinsics differ from P0's or its translation has y or z
  /// parts (not a rectified pair), or P1 has no baseline (-P1[0][3] / fx not > 0); an image
  /// folder holds a PNG not named NNNNNN.png, misses a number, or the two hold different
  /// numbers; the first image is unreadable or not 8-bit grey, or the principal point lies
  /// outside it; times.txt has a line that is not one finite number >= 0, times do not
  /// strictly increase, or it has other than one line per pair; a pose file has a row that
  /// is not 12 finite numbers or not a rigid transform, or other than one row per pair.
  /// Thread-safe.
  static std::optional<KittiOdometryReader> open(const std::string& folder, std::string* error);

  /// Number of stereo pairs. Thread-safe.
  size_t size() const { return times_ns_.size(); }

  /// Timestamp (nanoseconds) of the i-th pair; i < size(). Thread-safe.
  int64_t timestampNs(size_t i) const { return times_ns_.at(i); }

  /// Paths of the i-th pair's images; i < size(). Thread-safe.
  std::string leftImagePath(size_t i) const;
  std::string rightImagePath(size_t i) const;

  /// The rectified pair: P0's intrinsics at the images' size, the baseline from P1, the left
  /// camera as the body frame (T_B_L = identity). Thread-safe.
  const RectifiedStereoCalibration& calibration() const { return calibration_; }

  /// (size() - 1) / (last time - first time), Hz; 0 with one pair. Thread-safe.
  double rateHz() const { return rate_hz_; }

  /// True when a pose file was found and read; groundTruthPath() names it. Thread-safe.
  bool hasGroundTruth() const { return !poses_.empty(); }
  const std::string& groundTruthPath() const { return ground_truth_path_; }

  /// Human-readable remarks: the calib.txt rows read and not used, where the ground truth
  /// came from or that there is none. Thread-safe.
  const std::vector<std::string>& notes() const { return notes_; }

  /// The sequence folder this reader was opened on. Thread-safe.
  const std::string& folder() const { return folder_; }

  /// Reads the i-th pair into *frame (non-null). Returns false, leaving *frame untouched and
  /// writing a message naming the file to *error (if non-null), when i is out of range or an
  /// image is missing, unreadable, not 8-bit grey, or not the first image's size.
  /// Thread-safe.
  bool read(size_t i, KittiStereoFrame* frame, std::string* error) const;

 private:
  KittiOdometryReader() = default;

  std::string folder_;
  RectifiedStereoCalibration calibration_;
  double rate_hz_ = 0.0;
  std::vector<int64_t> times_ns_;
  std::vector<Transformationd> poses_;  // empty, or one per pair
  std::string ground_truth_path_;
  std::vector<std::string> notes_;
};

}  // namespace cblox
