#pragma once

#include <cstddef>
#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "core/geometry/image.h"
#include "core/geometry/pinhole_camera.h"
#include "core/geometry/se3.h"
#include "core/geometry/stereo_rig.h"
#include "drivers/calibration/stereo_rectifier.h"

namespace cblox {

/// One camera of a EuRoC rig as stored in its mav0/camX/sensor.yaml. Plain value type.
struct EurocCameraCalibration {
  Transformationd T_B_S;         // camera (sensor) S in the body frame B (the IMU in EuRoC)
  PinholeIntrinsics intrinsics;  // raw, distorted pinhole intrinsics; size = resolution
  std::string distortion_model;  // "radial-tangential" or "equidistant"
  /// radial-tangential: k1 k2 p1 p2 [k3] (OpenCV's order); equidistant: k1 k2 k3 k4.
  std::vector<double> distortion_coefficients;
  double rate_hz = 0.0;
};

/// One rectified stereo pair of a EuRoC sequence.
struct EurocStereoFrame {
  int64_t timestamp_ns = 0;  // the shared cam0/cam1 timestamp (nanoseconds, dataset clock)
  GrayImage left;            // rectified cam0, calibration().intrinsics
  GrayImage right;           // rectified cam1, same intrinsics, +baseline_m along x
  /// Rectified left camera L in the ground-truth world frame G (T_G_L = T_W_B * T_B_L), or
  /// std::nullopt when there is no ground truth at this timestamp.
  std::optional<Transformationd> T_G_L;
};

/// Reads a stereo sequence in the EuRoC / ASL folder layout:
///   mav0/cam0/sensor.yaml, mav0/cam1/sensor.yaml   T_BS, resolution, pinhole intrinsics,
///                                                  distortion, rate_hz ("%YAML:1.0" header)
///   mav0/camX/data.csv                             "#timestamp [ns],filename" lines
///   mav0/camX/data/<filename>                      8-bit grey images
///   mav0/state_groundtruth_estimate0/data.csv      optional: t [ns], p_RS_R xyz, q_RS wxyz, ...
/// cam0 and cam1 images are paired by identical timestamps. Both cameras are rectified once in
/// open() (cv::stereoRectify with zero disparity at infinity and alpha = 0, i.e. no black
/// borders, at the original image size; cv::fisheye for the equidistant model), and read()
/// returns rectified images. Immutable after open(): all member functions are thread-safe.
class EurocReader {
 public:
  /// Reader options; the defaults suit the EuRoC MAV dataset.
  struct Options {
    /// Ground truth is interpolated between two poses at most this far apart (seconds, > 0);
    /// farther apart, or outside the ground truth's time range, a frame has no ground truth.
    double groundtruth_max_gap_s = 0.05;

    /// Returns an empty string if the options are usable, else a message naming the first bad
    /// field. Thread-safe (pure).
    std::string validate() const;
  };

  /// Opens `folder`, which is either the folder holding mav0/ or mav0/ itself: reads and
  /// validates both sensor.yaml files, lists and pairs the frames, reads the ground truth if
  /// present and computes the rectification maps. Returns std::nullopt and, if error is
  /// non-null, a message naming the offending file (and line where there is one) when the
  /// options are invalid; the folder has no mav0/cam0 and mav0/cam1; a sensor.yaml is missing,
  /// unparsable, lacks a field or holds a bad value (T_BS not 16 numbers or not a rigid
  /// transform, camera_model not pinhole, unsupported distortion model or coefficient count,
  /// invalid intrinsics, non-positive rate_hz); the two cameras differ in resolution or
  /// distortion model; a data.csv line is malformed or its timestamps do not strictly
  /// increase; the ground-truth file is malformed; no complete pair remains; or the
  /// rectification fails or puts cam1 at -x of cam0. Unpaired entries and images missing on
  /// disk are skipped and described in skipped(). Thread-safe.
  static std::optional<EurocReader> open(const std::string& folder, const Options& options,
                                         std::string* error);

  /// Number of stereo pairs. Thread-safe.
  size_t size() const { return frames_.size(); }

  /// Timestamp (nanoseconds) of the i-th pair; i < size(). Thread-safe.
  int64_t timestampNs(size_t i) const { return frames_.at(i).timestamp_ns; }

  /// Paths of the i-th pair's raw (unrectified) cam0 and cam1 images; i < size().
  /// Thread-safe.
  const std::string& leftImagePath(size_t i) const { return frames_.at(i).left_path; }
  const std::string& rightImagePath(size_t i) const { return frames_.at(i).right_path; }

  /// Rectified stereo calibration shared by every frame: intrinsics from P1, baseline from
  /// P2 (metres, > 0) and the rectified left camera in the body frame. Thread-safe.
  const RectifiedStereoCalibration& calibration() const { return calibration_; }

  /// Raw calibration of cam0 (left) and cam1 (right) from sensor.yaml. Thread-safe.
  const EurocCameraCalibration& leftCamera() const { return cam0_; }
  const EurocCameraCalibration& rightCamera() const { return cam1_; }

  /// Camera rate from cam0's sensor.yaml (Hz). Thread-safe.
  double rateHz() const { return cam0_.rate_hz; }

  /// True if mav0/state_groundtruth_estimate0/data.csv was found and read. Thread-safe.
  bool hasGroundTruth() const { return has_groundtruth_; }

  /// One human-readable line per image or pair that open() skipped, e.g.
  /// "cam1/data/123.png: missing, frame 123 skipped". Thread-safe.
  const std::vector<std::string>& skipped() const { return skipped_; }

  /// Human-readable remarks about the sequence (absent ground truth, frames without ground
  /// truth, number of skipped entries). Thread-safe.
  const std::vector<std::string>& notes() const { return notes_; }

  /// The mav0 folder this reader was opened on. Thread-safe.
  const std::string& folder() const { return mav0_; }

  /// Reads and rectifies the i-th pair into *frame (non-null). Returns false, leaving *frame
  /// untouched and writing a message naming the file to *error (if non-null), when i is out of
  /// range or an image is unreadable, not 8-bit single-channel, or not the sensor.yaml
  /// resolution. Thread-safe.
  bool read(size_t i, EurocStereoFrame* frame, std::string* error) const;

 private:
  struct FrameFiles {
    int64_t timestamp_ns = 0;
    std::string left_path;
    std::string right_path;
    std::optional<Transformationd> T_G_L;
  };

  EurocReader() = default;

  std::string mav0_;
  EurocCameraCalibration cam0_;
  EurocCameraCalibration cam1_;
  RectifiedStereoCalibration calibration_;
  std::shared_ptr<const StereoRectifier> rectifier_;
  std::vector<FrameFiles> frames_;
  bool has_groundtruth_ = false;
  std::vector<std::string> skipped_;
  std::vector<std::string> notes_;
};

}  // namespace cblox
