#pragma once

#include <algorithm>
#include <vector>

// Shared analytic set-up for the integrator tests: a sphere of radius 0.5 m at the
// origin seen by a small pinhole camera from views around it.

#include <cmath>
#include <vector>

#include "core/geometry/depth_to_point_cloud.h"
#include "core/geometry/image.h"
#include "core/geometry/pinhole_camera.h"
#include "core/geometry/point_cloud.h"
#include "core/geometry/se3.h"
#include "core/tsdf/tsdf_interpolator.h"
#include "core/tsdf/tsdf_layer.h"
#include "drivers/synthetic/analytic_scene.h"
#include "drivers/synthetic/scenes.h"

namespace cblox::test {

inline constexpr double kSphereRadius = 0.5;
inline constexpr float kVoxelSize = 0.02f;

struct View {
  Transformationd T_G_C;
  DepthImage depth;
  ColorImage color;
};

inline PinholeCamera smallCamera() { return PinholeCamera({150.0, 150.0, 79.5, 59.5, 160, 120}); }

inline AnalyticScene sphereOnly() {
  AnalyticScene scene;
  scene.add(Sphere{Eigen::Vector3d::Zero(), kSphereRadius, CheckerTexture::solid({200, 60, 20})});
  return scene;
}

/// `count` views on a circle of radius 1.5 m (0.3 m above the centre) looking at the centre.
inline std::vector<View> renderSphereViews(int count) {
  const AnalyticScene scene = sphereOnly();
  const PinholeCamera camera = smallCamera();
  std::vector<View> views;
  for (const Transformationd& pose :
       makeOrbitTrajectory(Eigen::Vector3d::Zero(), 1.5, 0.3, count, Eigen::Vector3d::Zero())) {
    View view{pose, DepthImage(160, 120), ColorImage(160, 120)};
    scene.renderDepth(pose, camera, &view.depth, &view.color, 10.0);
    views.push_back(std::move(view));
  }
  return views;
}

inline PointCloud toCloud(const View& view) {
  return depthToPointCloud(view.depth, smallCamera(), &view.color, DepthConversionConfig{});
}

inline double trueSphereDistance(const Eigen::Vector3f& p) {
  return p.cast<double>().norm() - kSphereRadius;
}

/// Statistics of |stored - true| over observed voxels whose true distance is within
/// `band` metres of the surface.
struct DistanceErrors {
  size_t count = 0;
  double max_abs = 0.0;
  double rms = 0.0;
  double p99_abs = 0.0;  ///< 99th percentile of |error| (surfaceErrors only)
};

template <typename TrueDistance>
DistanceErrors compareToTruth(const TsdfLayer& layer, double band, TrueDistance truth) {
  DistanceErrors errors;
  double sum_sq = 0.0;
  for (const auto& [key, block] : layer.blocks()) {
    for (int i = 0; i < block->numVoxels(); ++i) {
      const TsdfVoxel& voxel = block->voxel(i);
      if (!voxel.observed()) continue;
      const double expected = truth(block->voxelCenter(block->localIndex(i)));
      if (std::abs(expected) > band) continue;
      const double error = std::abs(voxel.distance - expected);
      errors.max_abs = std::max(errors.max_abs, error);
      sum_sq += error * error;
      ++errors.count;
    }
  }
  errors.rms = errors.count ? std::sqrt(sum_sq / static_cast<double>(errors.count)) : 0.0;
  return errors;
}

/// Interpolated TSDF at points of the true sphere surface (latitudes -30..45 degrees,
/// which the orbiting views see): the zero crossing should be there, so this measures
/// where the integrated surface lies.
inline DistanceErrors surfaceErrors(const TsdfLayer& layer) {
  const TsdfInterpolator interpolator(layer);
  DistanceErrors errors;
  double sum_sq = 0.0;
  std::vector<double> abs_errors;
  for (int lat = -30; lat <= 45; lat += 5) {
    for (int lon = 0; lon < 360; lon += 3) {
      const double phi = lat * M_PI / 180.0, theta = lon * M_PI / 180.0;
      const Eigen::Vector3f p =
          (kSphereRadius * Eigen::Vector3d(std::cos(phi) * std::cos(theta),
                                           std::cos(phi) * std::sin(theta), std::sin(phi)))
              .cast<float>();
      float distance = 0.0f;
      if (!interpolator.getInterpolatedDistance(p, &distance)) continue;
      errors.max_abs = std::max(errors.max_abs, static_cast<double>(std::abs(distance)));
      abs_errors.push_back(std::abs(distance));
      sum_sq += static_cast<double>(distance) * distance;
      ++errors.count;
    }
  }
  errors.rms = errors.count ? std::sqrt(sum_sq / static_cast<double>(errors.count)) : 0.0;
  if (!abs_errors.empty()) {
    std::sort(abs_errors.begin(), abs_errors.end());
    errors.p99_abs = abs_errors[static_cast<size_t>(0.99 * static_cast<double>(abs_errors.size() - 1))];
  }
  return errors;
}

}  // namespace cblox::test
