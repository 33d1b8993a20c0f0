#pragma once

#include <limits>

#include <Eigen/Core>

#include "core/esdf/esdf_layer.h"
#include "core/esdf/esdf_voxel.h"

namespace cblox {

/// A distance-field answer at one point of a subvolume's frame.
///   state: unknown (never observed, or outside every block), free or occupied.
///   distance: metres to the nearest obstacle surface; negative inside obstacles; capped at
///     the layer's maxDistance() ("at least this far"). NaN when state is unknown: unknown
///     space has no distance, whatever obstacles are known around it.
///   bound: unknown answers only: the distance to the nearest obstacle the layer knows, as
///     its wave carried it there (band blocks and unobserved voxels carry them), capped at
///     maxDistance(): the clearance at the point is at most this, since that obstacle was
///     observed. NaN otherwise, and outside every block.
///   gradient: d distance / d position (about unit length, pointing away from the nearest
///     obstacle), only when has_gradient; NaN otherwise. For an unknown answer, the
///     gradient of bound.
struct DistanceSample {
  VoxelState state = VoxelState::kUnknown;
  float distance = std::numeric_limits<float>::quiet_NaN();
  float bound = std::numeric_limits<float>::quiet_NaN();
  Eigen::Vector3f gradient = Eigen::Vector3f::Constant(std::numeric_limits<float>::quiet_NaN());
  bool has_gradient = false;
};

/// The field's value at one voxel: sites (occupied voxels and the free side's near-surface
/// voxels) their value (EsdfIntegrator: the TSDF distance, gradient-normalised on the free
/// side); other voxels the distance the wave carried to them through
/// their site (EsdfIntegrator), or maxDistance() without a site; capped at maxDistance()
/// (see EsdfVoxel). No site is looked up: one voxel read per answer. Unknown voxels get the same
/// value (the distance to the nearest obstacle known). False, with nothing written, when the
/// voxel's block is absent. Thread-safe against other readers.
bool voxelDistance(const EsdfLayer& layer, const GlobalVoxelIndex& index, VoxelState* state,
                   float* distance);

/// The answer of the voxel that contains `point`; no gradient.
DistanceSample queryNearest(const EsdfLayer& layer, const Eigen::Vector3f& point);

/// Trilinear interpolation of the eight voxel centres around `point`, with the analytic
/// gradient, when all eight are observed (free or occupied); state is then occupied where
/// the interpolated distance is <= 0, free elsewhere. When any of the eight is unknown or
/// absent, the answer is queryNearest's (no gradient); when that is unknown and all eight
/// voxels are in blocks, its bound is the interpolation of their values, with its gradient.
DistanceSample queryInterpolated(const EsdfLayer& layer, const Eigen::Vector3f& point);

/// A free answer lowered beside an obstacle by a margin of m voxels (EsdfConfig::
/// surface_margin_voxels): distance d (metres, voxel size h) becomes d - m h up to
/// (1 + m) h, then less and less, linearly, down to d at (2 + m) h and beyond; never below 0.
/// So an answer of at most (1 + m) voxels becomes one of at most one voxel, and the answer
/// keeps growing with d. *slope (when not null) receives d answer / d d: 1 + m in the
/// tapering voxel, 1 elsewhere (also where the answer is held at 0, so that a gradient keeps
/// its direction). Thread-safe (pure).
double lowerBesideSurface(double distance, double voxel, double margin_voxels,
                          double* slope = nullptr);

}  // namespace cblox
