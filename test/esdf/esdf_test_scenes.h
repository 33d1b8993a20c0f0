#pragma once

// Analytic TSDFs for the distance-field tests: exact signed distance functions written into
// a TsdfLayer as an integrator would leave them (truncated, deep interiors unobserved).

#include <algorithm>
#include <cmath>
#include <functional>

#include <Eigen/Core>

#include "core/tsdf/tsdf_layer.h"

namespace cblox::esdf_test {

using Sdf = std::function<float(const Eigen::Vector3f&)>;

/// Allocates every block that overlaps [lo, hi] and writes each voxel centre's signed
/// distance clamped to +-truncation with weight 1; voxels deeper than the truncation inside
/// an obstacle stay unobserved (weight 0), as behind a surface seen by a camera. Blocks
/// whose voxels change are marked updated.
inline void writeTsdf(TsdfLayer* layer, const Sdf& sdf, const Eigen::Vector3f& lo,
                      const Eigen::Vector3f& hi, float truncation) {
  const BlockIndex b0 = layer->blockIndexFromPoint(lo);
  const BlockIndex b1 = layer->blockIndexFromPoint(hi);
  for (int z = b0.z(); z <= b1.z(); ++z) {
    for (int y = b0.y(); y <= b1.y(); ++y) {
      for (int x = b0.x(); x <= b1.x(); ++x) {
        Block* block = layer->allocateBlock(BlockIndex(x, y, z));
        bool changed = false;
        for (int i = 0; i < block->numVoxels(); ++i) {
          TsdfVoxel& v = block->voxel(i);
          const float d = sdf(block->voxelCenter(block->localIndex(i)));
          TsdfVoxel next;
          if (d >= -truncation) {
            next.distance = std::clamp(d, -truncation, truncation);
            next.weight = 1.0f;
          }
          if (next.distance != v.distance || next.weight != v.weight) {
            v = next;
            changed = true;
          }
        }
        if (changed) block->setUpdated(true);
      }
    }
  }
}

/// Obstacle x < x0 (signed distance x - x0).
inline Sdf planeX(float x0) {
  return [x0](const Eigen::Vector3f& p) { return p.x() - x0; };
}

/// Solid ball.
inline Sdf ball(const Eigen::Vector3f& centre, float radius) {
  return [centre, radius](const Eigen::Vector3f& p) { return (p - centre).norm() - radius; };
}

/// Solid axis-aligned box [lo, hi] (exact signed distance, also outside corners).
inline Sdf box(const Eigen::Vector3f& lo, const Eigen::Vector3f& hi) {
  return [lo, hi](const Eigen::Vector3f& p) {
    const Eigen::Vector3f centre = 0.5f * (lo + hi);
    const Eigen::Vector3f half = 0.5f * (hi - lo);
    const Eigen::Vector3f q = (p - centre).cwiseAbs() - half;
    return q.cwiseMax(0.0f).norm() + std::min(q.maxCoeff(), 0.0f);
  };
}

/// Union of two obstacles.
inline Sdf unite(const Sdf& a, const Sdf& b) {
  return [a, b](const Eigen::Vector3f& p) { return std::min(a(p), b(p)); };
}

/// Free space everywhere (an observed empty volume).
inline Sdf empty() {
  return [](const Eigen::Vector3f&) { return 1e9f; };
}

}  // namespace cblox::esdf_test
