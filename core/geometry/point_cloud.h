#pragma once

#include <cstddef>
#include <vector>

#include <Eigen/Core>

#include "core/geometry/color.h"
#include "core/geometry/se3.h"

namespace cblox {

/// Points (metres, in whatever frame the owner names) with optional per-point colour.
/// Invariant: colors is empty or has exactly points.size() entries.
/// Plain value type: concurrent reads are thread-safe, writes need external synchronisation.
struct PointCloud {
  std::vector<Eigen::Vector3f> points;
  std::vector<Color> colors;  // empty, or same size as points

  /// Number of points.
  size_t size() const { return points.size(); }
  /// True if the cloud carries colours (colors is non-empty).
  bool hasColors() const { return !colors.empty(); }
  /// True if the invariant holds (colors empty or same size as points).
  bool isConsistent() const { return colors.empty() || colors.size() == points.size(); }
  /// Removes all points and colours (keeps capacity).
  void clear() {
    points.clear();
    colors.clear();
  }
  /// Reserves capacity for n points and n colours.
  void reserve(size_t n) {
    points.reserve(n);
    colors.reserve(n);
  }
};

/// Returns cloud_B expressed in frame A: p_A = T_A_B * p_B for every point; colours are copied.
/// Units: metres. Thread-safe (pure).
PointCloud transformPointCloud(const Transformation& T_A_B, const PointCloud& cloud_B);

}  // namespace cblox
