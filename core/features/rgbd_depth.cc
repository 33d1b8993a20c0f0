#include "core/features/rgbd_depth.h"

#include <cmath>
#include <stdexcept>
#include <string>

namespace cblox {

StereoDepth depthFromRgbd(const std::vector<Keypoint>& keypoints, const DepthImage& depth,
                          double bf) {
  if (depth.empty()) throw std::invalid_argument("depthFromRgbd: empty depth image");
  if (depth.data.size() != static_cast<size_t>(depth.width) * static_cast<size_t>(depth.height)) {
    throw std::invalid_argument("depthFromRgbd: depth image data holds " +
                                std::to_string(depth.data.size()) + " pixels, not " +
                                std::to_string(depth.width) + "x" + std::to_string(depth.height));
  }
  if (!(bf > 0.0) || !std::isfinite(bf)) {
    throw std::invalid_argument("depthFromRgbd: bf must be finite and > 0, got " +
                                std::to_string(bf));
  }
  StereoDepth out;
  out.right_u.assign(keypoints.size(), -1.0f);
  out.depth.assign(keypoints.size(), -1.0f);
  out.right_index.assign(keypoints.size(), -1);
  for (size_t i = 0; i < keypoints.size(); ++i) {
    const Keypoint& kp = keypoints[i];
    if (!std::isfinite(kp.u) || !std::isfinite(kp.v)) continue;
    const long u = std::lround(kp.u), v = std::lround(kp.v);
    if (u < 0 || v < 0 || u >= depth.width || v >= depth.height) continue;
    const float z = depth(static_cast<int>(u), static_cast<int>(v));
    if (!(z > 0.0f) || !std::isfinite(z)) continue;
    out.depth[i] = z;
    out.right_u[i] = static_cast<float>(static_cast<double>(kp.u) - bf / static_cast<double>(z));
  }
  return out;
}

}  // namespace cblox
