#pragma once

// Frames for the feature tests, rendered or read once per test binary.

#include <string>
#include <vector>

#include <opencv2/core.hpp>

#include "core/geometry/image.h"
#include "drivers/frame_source.h"

namespace cblox::test {

/// A rectified stereo pair (with exact depth for simulator frames) and its calibration.
struct StereoFrame {
  std::string name;
  GrayImage left, right;
  DepthImage depth;  // registered to the left camera; empty for real data
  double fx = 0.0, baseline_m = 0.0;
};

/// `count` frames of the built-in scene ("room", "hall", "town") from openFrameSource
/// ("sim:<scene>", loop trajectory, exact images), spread 2 s apart along the trajectory.
/// Rendered on first use and cached; fails the calling test (ADD_FAILURE) and returns fewer
/// frames if the source cannot be opened.
const std::vector<StereoFrame>& simFrames(const std::string& scene, size_t count);

/// Every 10th of the 40 EuRoC pairs in ../shared/data/euroc-v101-micro, or an empty
/// vector when the data is absent. Read on first use and cached.
const std::vector<StereoFrame>& eurocFrames();

/// Path of the EuRoC test data.
std::string eurocDir();

/// A cv::Mat view of a grey image (no copy).
cv::Mat matView(const GrayImage& image);

}  // namespace cblox::test
