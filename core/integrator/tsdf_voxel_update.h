#pragma once

#include <algorithm>
#include <cmath>
#include <cstdint>

#include "core/geometry/color.h"
#include "core/integrator/integrator_config.h"
#include "core/tsdf/voxel.h"

namespace cblox {

/// The per-voxel fusion rule shared by every integrator (voxblox's rule):
/// weighted running average of the signed distance, clamped to +-truncation, weight
/// saturating at max_weight, linear weight drop-off behind the surface, colour blended
/// per ColorBlending. Not thread-safe: the caller owns the voxel (see Block).
class TsdfVoxelUpdater {
 public:
  TsdfVoxelUpdater(const IntegratorConfig& config, float voxel_size)
      : truncation_(config.truncation_distance_m),
        max_weight_(config.max_weight),
        dropoff_start_(voxel_size),
        dropoff_scale_(1.0f / (config.truncation_distance_m - voxel_size)),
        use_dropoff_(config.use_weight_dropoff && config.truncation_distance_m > voxel_size),
        inverse_square_(config.weight_model == WeightModel::kInverseSquare),
        blending_(config.color_blending) {}

  /// Truncation distance, metres.
  float truncation() const { return truncation_; }
  /// The rule's constants, for vectorised copies of update() that must agree with it bit
  /// for bit (ProjectiveVoxelRows).
  float maxWeight() const { return max_weight_; }
  /// Drop-off: with usesDropoff(), a measurement with sdf < -dropoffStart() has its weight
  /// multiplied by (truncation + sdf) * dropoffScale().
  bool usesDropoff() const { return use_dropoff_; }
  float dropoffStart() const { return dropoff_start_; }
  float dropoffScale() const { return dropoff_scale_; }
  bool inverseSquareWeight() const { return inverse_square_; }
  ColorBlending blending() const { return blending_; }

  /// Weight of a measurement at camera depth `z` (metres, > 0).
  float measurementWeight(float z) const { return inverse_square_ ? 1.0f / (z * z) : 1.0f; }

  /// Fuses one measurement: `sdf` is the signed distance of the voxel centre to the
  /// measured surface along the ray (metres, positive on the sensor side). Voxels more
  /// than one truncation behind the surface are not touched. Colour is blended only
  /// within the truncation band (|sdf| < truncation): free-space measurements carry no
  /// surface colour, and meshes read colours at the zero crossing. Returns true if the
  /// voxel was updated.
  bool update(float sdf, float weight, const Color& color, TsdfVoxel* voxel) const {
    if (sdf < -truncation_) return false;
    if (use_dropoff_ && sdf < -dropoff_start_) {
      weight *= (truncation_ + sdf) * dropoff_scale_;
      if (weight <= 0.0f) return false;
    }
    const float old_weight = voxel->weight;
    const float new_weight = old_weight + weight;
    const float inv_new_weight = 1.0f / new_weight;
    const bool in_band = sdf < truncation_;
    const float measured = in_band ? sdf : truncation_;
    voxel->distance =
        std::clamp((voxel->distance * old_weight + measured * weight) * inv_new_weight,
                   -truncation_, truncation_);
    voxel->weight = std::min(new_weight, max_weight_);
    if (!in_band) return true;
    if (blending_ == ColorBlending::kWeightedAverage) {
      // Fixed point: the new colour's share in 1/256, rounded; (a + b) == 256 keeps the
      // result a convex combination (no overflow, exact for equal colours).
      const uint32_t b = static_cast<uint32_t>(weight * inv_new_weight * 256.0f + 0.5f);
      const uint32_t a = 256u - b;
      voxel->color.r = static_cast<uint8_t>((voxel->color.r * a + color.r * b + 128u) >> 8);
      voxel->color.g = static_cast<uint8_t>((voxel->color.g * a + color.g * b + 128u) >> 8);
      voxel->color.b = static_cast<uint8_t>((voxel->color.b * a + color.b * b + 128u) >> 8);
    } else if (blending_ == ColorBlending::kOverwrite) {
      voxel->color = color;
    }
    return true;
  }

 private:
  float truncation_;
  float max_weight_;
  float dropoff_start_;
  float dropoff_scale_;
  bool use_dropoff_;
  bool inverse_square_;
  ColorBlending blending_;
};

}  // namespace cblox
