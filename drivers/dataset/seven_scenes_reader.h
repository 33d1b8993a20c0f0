#pragma once

#include <cstddef>
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "core/geometry/image.h"
#include "core/geometry/pinhole_camera.h"
#include "core/geometry/se3.h"

namespace cblox {

/// One frame of a 7-Scenes sequence. Note the colour camera is not registered to the depth
/// camera in 7-Scenes; both images are delivered as stored.
struct SevenScenesFrame {
  int64_t index = 0;      // the NNNNNN of frame-NNNNNN.*
  Transformationd T_G_C;  // camera-to-world pose from the pose file (G = the dataset's world)
  DepthImage depth;       // metres; 0 = invalid (stored as 0 or 65535 mm)
  ColorImage color;       // RGB
};

/// Reads a folder in the 7-Scenes frame layout:
///   camera-intrinsics.txt      3x3 K of the depth camera
///   frame-NNNNNN.color.png     8-bit RGB, or instead
///   frame-NNNNNN.color.jpg     the same as JPEG (as some public copies ship it)
///   frame-NNNNNN.depth.png     16-bit single-channel depth in millimetres, 0/65535 invalid
///   frame-NNNNNN.pose.txt      4x4 row-major T_W_C
/// Frames are discovered by listing the folder and sorted by number (gaps are allowed). The
/// colour format is detected per frame, so a folder may mix the two; a frame with both files
/// uses the PNG (lossless). Depth and pose are read the same way whatever the colour format.
/// Immutable after open(): all member functions are thread-safe.
class SevenScenesReader {
 public:
  /// Opens `folder`: reads the intrinsics (image size taken from the first depth image) and
  /// lists the frames. Returns std::nullopt and, if error is non-null, a message naming the
  /// offending file when the folder is unreadable, camera-intrinsics.txt is missing or not a
  /// valid K, there are no frames, a frame lacks one of its three files, or the first depth
  /// image is unreadable. Thread-safe.
  static std::optional<SevenScenesReader> open(const std::string& folder, std::string* error);

  /// Number of frames. Thread-safe.
  size_t size() const { return frames_.size(); }

  /// Depth camera intrinsics (width and height from the first depth image). Thread-safe.
  const PinholeIntrinsics& depthIntrinsics() const { return intrinsics_; }

  /// Frame number (NNNNNN) of the i-th frame in sorted order; i < size() (else throws
  /// std::out_of_range). Thread-safe.
  int64_t frameIndex(size_t i) const { return frames_.at(i).number; }

  /// Path of the i-th frame's colour image, "<folder>/frame-NNNNNN.color.png" or ".color.jpg"
  /// (see the class comment); i < size() (else throws std::out_of_range). Thread-safe.
  std::string colorPath(size_t i) const { return frames_.at(i).stem + frames_.at(i).color_suffix; }

  /// The folder this reader was opened on. Thread-safe.
  const std::string& folder() const { return folder_; }

  /// Reads the i-th frame (sorted order) into *frame (non-null). Returns false, leaving
  /// *frame untouched and writing a message naming the file to *error (if non-null), when i
  /// is out of range; the pose file is unreadable or malformed (not 16 numbers, non-numeric,
  /// last row not 0 0 0 1, rotation not orthonormal within 1e-3 or a reflection); the depth
  /// image is unreadable, not 16-bit single-channel or not the intrinsics' size; or the colour
  /// image is unreadable or not the depth image's size. Thread-safe.
  bool read(size_t i, SevenScenesFrame* frame, std::string* error) const;

 private:
  struct FrameFiles {
    int64_t number = 0;
    std::string stem;                         // "<folder>/frame-NNNNNN"
    const char* color_suffix = ".color.png";  // or ".color.jpg"; static storage
  };

  SevenScenesReader() = default;

  std::string folder_;
  PinholeIntrinsics intrinsics_;
  std::vector<FrameFiles> frames_;
};

}  // namespace cblox
