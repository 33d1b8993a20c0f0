#pragma once

// The analytic room as the mapper's tests feed it: small depth frames along an orbit with
// their exact poses, and their conversion into the Mapper's inputs.

#include <cstdint>
#include <vector>

#include "core/geometry/se3.h"
#include "core/mapping/depth_frame.h"
#include "core/mapping/pose_buffer.h"
#include "drivers/synthetic/scenes.h"
#include "drivers/synthetic/synthetic_frame_source.h"

namespace cblox {

inline PinholeIntrinsics smallCamera() { return {120.0, 120.0, 79.5, 59.5, 160, 120}; }

/// `count` frames of the analytic room along a 1.5 m orbit, 10 Hz.
inline std::vector<SyntheticFrame> renderRoom(int count) {
  SyntheticDepthSource source(
      makeDemoRoom(), smallCamera(),
      makeOrbitTrajectory(Eigen::Vector3d(0, 0, 0), 1.5, 1.4, count, Eigen::Vector3d(0, 0, 1.0)),
      10.0, 6.0);
  std::vector<SyntheticFrame> frames(source.size());
  for (SyntheticFrame& frame : frames) source.next(&frame);
  return frames;
}

inline const std::vector<SyntheticFrame>& roomFrames() {
  static const std::vector<SyntheticFrame> frames = renderRoom(24);
  return frames;
}

inline int64_t utimeOf(const SyntheticFrame& frame) { return frame.timestamp_ns / 1000; }

inline DepthFrame depthFrame(const SyntheticFrame& frame, int64_t frame_id) {
  DepthFrame depth;
  depth.utime = utimeOf(frame);
  depth.frame_id = frame_id;
  depth.depth = frame.depth;
  depth.color = frame.color;
  depth.intrinsics = smallCamera();
  depth.min_depth_m = 0.1f;
  depth.max_depth_m = 10.0f;
  return depth;
}

inline TimedPose groundTruthPose(int64_t utime, const Transformationd& T_G_C) {
  TimedPose pose;
  pose.utime = utime;
  pose.T_G_C = T_G_C;
  return pose;
}

}  // namespace cblox
