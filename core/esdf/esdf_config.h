#pragma once

#include <string>

namespace cblox {

/// Settings of one subvolume's distance field (EsdfIntegrator).
struct EsdfConfig {
  /// Distances are computed up to this far from the nearest obstacle, metres; a free voxel
  /// farther away holds exactly max_distance_m ("at least this far"). Finite and > 0.
  float max_distance_m = 2.0f;
  /// A TSDF voxel with weight below this is unknown space: neither free nor an obstacle.
  /// Finite and >= 0.
  float min_weight = 1e-4f;
  /// Rings of blocks around the TSDF's blocks that the field also covers, every voxel
  /// unknown there: the wave carries the distance to this subvolume's obstacles into space
  /// it never observed, where another subvolume may have observed it free (PlanningMap
  /// bounds such an answer by it). 0 = the TSDF's blocks only (a single volume needs no
  /// band). Each ring costs about as many blocks as a surface's own. In [0, 2].
  int band_blocks = 0;
  /// Free answers beside an obstacle are lowered by this many voxels (PlanningMap, see
  /// lowerBesideSurface()): a field sampled at voxel centres, from a TSDF that rounds convex
  /// edges off, overstates the distance beside a surface by up to about half a voxel; with
  /// the margin a point within one voxel of an observed surface is not answered farther
  /// than one voxel. 0 answers the field's own values. Finite, in [0, 1].
  float surface_margin_voxels = 0.5f;

  /// Empty when valid, otherwise a message naming the offending field. Thread-safe.
  std::string validate() const;
};

}  // namespace cblox
