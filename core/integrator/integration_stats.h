#pragma once

#include <cstddef>

namespace cblox {

/// What one integrated frame did. Counters are exact (summed over threads).
struct IntegrationStats {
  size_t points_in = 0;            ///< points (or pixels) offered
  size_t points_invalid = 0;       ///< non-finite coordinates or depth <= 0
  size_t points_out_of_range = 0;  ///< ray length outside [min_ray_length, max_ray_length]
  size_t points_subsampled = 0;    ///< fast: rejected by the start-voxel set
  size_t points_not_reached = 0;   ///< fast: not visited because the time budget ran out
  size_t rays_cast = 0;            ///< rays whose voxels were walked
  size_t rays_stopped_early = 0;   ///< fast: rays ended by max_consecutive_ray_collisions
  size_t rays_cut_by_budget = 0;   ///< fast: rays cast but left unfinished by the budget
  size_t voxel_updates = 0;        ///< voxel updates applied
  size_t blocks_allocated = 0;     ///< blocks added to the layer by this frame
  size_t blocks_not_reached = 0;   ///< projective: blocks skipped because the budget ran out
  bool budget_exhausted = false;   ///< fast, projective: the time budget cut this frame short
  double seconds = 0.0;            ///< wall time of the whole call

  IntegrationStats& operator+=(const IntegrationStats& o) {
    points_in += o.points_in;
    points_invalid += o.points_invalid;
    points_out_of_range += o.points_out_of_range;
    points_subsampled += o.points_subsampled;
    points_not_reached += o.points_not_reached;
    rays_cast += o.rays_cast;
    rays_stopped_early += o.rays_stopped_early;
    rays_cut_by_budget += o.rays_cut_by_budget;
    voxel_updates += o.voxel_updates;
    blocks_allocated += o.blocks_allocated;
    blocks_not_reached += o.blocks_not_reached;
    budget_exhausted = budget_exhausted || o.budget_exhausted;
    return *this;
  }
};

}  // namespace cblox
