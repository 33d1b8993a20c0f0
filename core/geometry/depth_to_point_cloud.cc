#include "core/geometry/depth_to_point_cloud.h"

#include <cmath>
#include <sstream>
#include <stdexcept>
#include <vector>

namespace cblox {
namespace {

std::string sizeString(int width, int height) {
  return std::to_string(width) + "x" + std::to_string(height);
}

}  // namespace

std::string DepthConversionConfig::validate() const {
  std::ostringstream os;
  if (!(min_depth_m > 0.0f) || !std::isfinite(min_depth_m)) {
    os << "min_depth_m must be finite and > 0, got " << min_depth_m;
  } else if (!(max_depth_m > min_depth_m) || !std::isfinite(max_depth_m)) {
    os << "max_depth_m must be finite and > min_depth_m (" << min_depth_m << "), got "
       << max_depth_m;
  } else if (stride < 1) {
    os << "stride must be >= 1, got " << stride;
  }
  return os.str();
}

PointCloud depthToPointCloud(const DepthImage& depth, const PinholeCamera& camera,
                             const ColorImage* color, const DepthConversionConfig& config,
                             DepthConversionStats* stats) {
  const std::string error = config.validate();
  if (!error.empty()) throw std::invalid_argument("DepthConversionConfig: " + error);
  const PinholeIntrinsics& in = camera.intrinsics();
  if (depth.width != in.width || depth.height != in.height ||
      depth.data.size() != static_cast<size_t>(depth.width) * depth.height) {
    throw std::invalid_argument("depthToPointCloud: depth image is " +
                                sizeString(depth.width, depth.height) + " but the camera is " +
                                sizeString(in.width, in.height));
  }
  if (color != nullptr && (!color->sameSize(depth) || color->data.size() != depth.data.size())) {
    throw std::invalid_argument("depthToPointCloud: color image is " +
                                sizeString(color->width, color->height) +
                                " but the depth image is " + sizeString(depth.width, depth.height));
  }

  const int stride = config.stride;
  // Per-column and per-row ray factors, same arithmetic as PinholeCamera::backProject.
  std::vector<double> x_factor;
  for (int u = 0; u < depth.width; u += stride) x_factor.push_back((u - in.cx) / in.fx);

  DepthConversionStats counts;
  PointCloud cloud;
  const size_t sampled =
      x_factor.size() * static_cast<size_t>((depth.height + stride - 1) / stride);
  // Sized once and written by index, then cut to the valid count: no per-point growth
  // checks in the loop.
  cloud.points.resize(sampled);
  if (color != nullptr) cloud.colors.resize(sampled);
  Eigen::Vector3f* const points = cloud.points.data();
  Color* const colors = cloud.colors.data();
  size_t count = 0;
  const float min_depth = config.min_depth_m, max_depth = config.max_depth_m;
  for (int v = 0; v < depth.height; v += stride) {
    const double y_factor = (v - in.cy) / in.fy;
    const float* row = &depth.data[static_cast<size_t>(v) * static_cast<size_t>(depth.width)];
    for (int u = 0, i = 0; u < depth.width; u += stride, ++i) {
      const float d = row[u];
      // Fast path first: NaN and every non-positive depth fail this test (min_depth > 0).
      if (d >= min_depth && d <= max_depth) {
        points[count] = Eigen::Vector3f(static_cast<float>(x_factor[i] * d),
                                        static_cast<float>(y_factor * d), d);
        if (color != nullptr) colors[count] = (*color)(u, v);
        ++count;
      } else if (!std::isfinite(d)) {
        ++counts.non_finite;
      } else if (d <= 0.0f) {
        ++counts.non_positive;
      } else {
        ++counts.out_of_range;
      }
    }
  }
  counts.valid = count;
  cloud.points.resize(count);
  if (color != nullptr) cloud.colors.resize(count);
  if (stats != nullptr) *stats = counts;
  return cloud;
}

}  // namespace cblox
