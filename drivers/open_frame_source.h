#pragma once

#include <cstddef>
#include <memory>
#include <string>
#include <vector>

#include "drivers/dataset/euroc_reader.h"
#include "drivers/dataset/tum_rgbd_reader.h"
#include "drivers/frame_source.h"
#include "drivers/libcamera/libcamera_source_config.h"
#include "drivers/sim/sim_source.h"
#include "drivers/v4l2/v4l2_source_config.h"

namespace cblox {

/// How to open a source named by a spec string (see openFrameSource). Plain value type.
struct SourceConfig {
  /// Simulator: the trajectory, either a kind ("loop", "orbit", "lawnmower", "figure-eight")
  /// or the path of a TUM trajectory file (poses of the left camera).
  std::string trajectory = "loop";
  int laps = 1;
  /// Simulator: rig, renderer, noise and rate. For built-in scenes, depth_max_m and the
  /// texture wavelength are taken from the scene unless `keep_rig_range` is true.
  SimSourceConfig sim;
  bool keep_rig_range = false;
  /// Datasets.
  EurocReader::Options euroc;
  TumRgbdReader::Options tum;
  /// Stop after this many frames (0 = all).
  size_t max_frames = 0;
  /// Cameras: the stream settings (devices / camera id come from the spec).
  V4l2SourceConfig v4l2;
  LibcameraSourceConfig libcamera;
  /// Cameras with two views (v4l2-stereo, side-by-side): the raw rig's calibration (Kalibr
  /// camchain or OpenCV YAML/XML, drivers/calibration/calibration_file.h). When set, frames
  /// are rectified at capture and SourceInfo::stereo is the rectified calibration; empty =
  /// deliver the raw views (no stereo calibration, so no tracking or stereo depth).
  std::string calibration_file;
};

/// Opens a capture source from a spec:
///   sim:room | sim:hall | sim:town   built-in procedural scene (exact ground truth)
///   sim:<mesh.ply|mesh.obj>          any triangle mesh; trajectory must be a TUM file or
///                                    "orbit" (around the mesh's bounding box)
///   euroc:<folder>                   EuRoC/ASL stereo folder (with or without mav0/)
///   kitti:<folder>                   KITTI odometry grey stereo sequence (image_0/,
///                                    image_1/, calib.txt, times.txt, poses.txt or
///                                    ../../poses/NN.txt)
///   tum:<folder>                     TUM RGB-D folder
///   7scenes:<folder>                 7-Scenes frame folder
///   v4l2:/dev/videoN                 one V4L2 device; options.v4l2.mode says mono, depth
///                                    (Z16) or side_by_side
///   v4l2-stereo:/dev/videoL,/dev/videoR  two V4L2 cameras paired by timestamp
///   libcamera:CAMERA_ID              a libcamera camera (id as `cam --list` prints it, or an
///                                    index); options.libcamera.mode mono or side_by_side
/// A camera that cannot be opened (missing, busy, not a capture device, a format or size it
/// does not offer: the message names the device and the formats it offers) gives nullptr.
/// Returns nullptr and a message (naming the file and line where there is one) when the spec
/// is unknown or the source cannot be opened. Problems that do not stop the source are
/// appended to `*warnings` when it is not null, one sentence each, for the caller to print on
/// stderr: a sim mesh with non-manifold edges (see loadSceneMesh; also in the source's
/// info().notes as "warning: ..."), a calibration_file given to a source that carries its own
/// calibration. Thread-safe (no shared state).
std::unique_ptr<FrameSource> openFrameSource(const std::string& spec, const SourceConfig& options,
                                             std::string* error,
                                             std::vector<std::string>* warnings = nullptr);

/// True for the specs of live cameras (v4l2:, v4l2-stereo:, libcamera:), which
/// SourceConfig::calibration_file and a capture's device wait apply to. Thread-safe (pure).
bool isCameraSpec(const std::string& spec);

/// For sim sources: the ground-truth mesh of the scene a spec names (built-in or loaded), or
/// nullptr with a message. A loaded mesh's warnings (loadSceneMesh's report, e.g. non-manifold
/// edges, which are accepted) are appended to `*warnings` when it is not null. Thread-safe.
std::shared_ptr<const Mesh> loadSimSceneMesh(const std::string& spec, std::string* error,
                                             std::vector<std::string>* warnings = nullptr);

}  // namespace cblox
