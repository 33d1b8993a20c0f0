#pragma once

// A depth frame as the mapper takes it (decoded from depth_frame_t).

#include <cstdint>

#include "core/geometry/image.h"
#include "core/geometry/pinhole_camera.h"
#include "core/geometry/se3.h"

namespace cblox {

/// One depth frame as the mapper takes it (decoded from depth_frame_t). Plain value type.
struct DepthFrame {
  int64_t utime = 0;             ///< capture time, microseconds (matched with pose time stamps)
  int64_t frame_id = 0;          ///< capture frame counter (ground-truth mode: keyframe ids)
  DepthImage depth;              ///< metres along the depth camera's z; 0/NaN = no measurement
  ColorImage color;              ///< registered to depth, same size; empty = no colour
  PinholeIntrinsics intrinsics;  ///< of the depth camera (undistorted)
  /// Depth camera D in the frame the poses refer to (the body/primary camera B): the camera
  /// pose used for integration is T_G_D = T_G_B * T_B_D. Identity for a registered RGB-D
  /// camera that is itself the tracked camera.
  Transformationd T_B_D;
  /// Valid depth range of the sensor, metres; readings outside are ignored.
  float min_depth_m = 0.0f;
  float max_depth_m = 1e9f;
};

}  // namespace cblox
