#pragma once

#include <cstdint>
#include <vector>

#include "core/geometry/image.h"
#include "core/geometry/pinhole_camera.h"
#include "core/geometry/se3.h"
#include "core/integrator/approx_hash_set.h"
#include "core/integrator/block_cube_set.h"
#include "core/integrator/integration_stats.h"
#include "core/integrator/integrator_config.h"
#include "core/integrator/projective_voxel_rows.h"
#include "core/integrator/rectangle_max_table.h"
#include "core/tsdf/tsdf_layer.h"

namespace cblox {

/// Integrates depth images by voxel projection (KinectFusion / Open3D style): each voxel
/// of the blocks within truncation of the measured surface is visited once per frame,
/// projected into the image (nearest pixel), and updated with the distance to the
/// measured surface along that pixel's ray, (d - z) * ||(x_n, y_n, 1)|| where d is the
/// pixel's depth, z the voxel centre's depth and (x_n, y_n) the pixel's normalised
/// coordinates (a per-pixel factor computed once per camera, as Open3D does).
///
/// Block search: the image is cut into 8x8-pixel cells. A cell's valid depths, in order,
/// fall into groups wherever two neighbours are more than the truncation distance apart
/// (one group on a surface, one per surface across a depth edge). Each group contributes
/// the blocks around the segment of the cell's centre ray between its nearest and farthest
/// depth, widened by the truncation and the cell's lateral extent, so the empty space
/// between a foreground and a background surface gets no blocks. No voxel within
/// truncation of a measured point is missed. A block found this way is then screened
/// (ProjectiveBlockScreen) in four parts, its rows of voxels split by halving y and z: a
/// part whose voxels all lie more than the truncation behind the deepest valid pixel under
/// it, or outside the image, is not visited, and a block with no part left is not
/// allocated. The blocks found so far are kept in one bit each of a cube of blocks around
/// the sensor (BlockCubeSet), as neighbouring cells find mostly the same blocks.
///
/// Voxels are updated a row at a time (ProjectiveVoxelRows: eight voxels at once on AVX2
/// CPUs, IntegratorConfig::vectorized).
///
/// Free space: with IntegratorConfig::projective_carving_depth_m > 0 each cell also
/// contributes the blocks around its centre ray from min_ray_length_m to its nearest depth
/// less the truncation (at most that carving depth), and their voxels in front of the
/// surface are updated to +truncation as the band's are. Without it (0, the default), it
/// maps no free space outside the blocks of the truncation band, and it is much faster
/// than the ray-casting integrators. Every voxel is owned by exactly one
/// thread per frame (work is split by block), so results do not depend on num_threads.
/// Uses truncation, weights, ray-length limits, colour blending and num_threads from
/// IntegratorConfig; the fast-integrator settings and voxel carving do not apply.
///
/// Thread safety: one call at a time per integrator, and nothing else may touch the layer
/// during the call.
class ProjectiveTsdfIntegrator {
 public:
  /// Throws std::invalid_argument naming the invalid field, or if layer is null.
  ProjectiveTsdfIntegrator(const IntegratorConfig& config, TsdfLayer* layer);

  /// `depth` holds z along the optical axis in metres (0, negative or non-finite =
  /// no measurement; counted as invalid). `color`, when not null, must be registered to
  /// the depth image and have its size. `camera` must match the depth image size.
  /// Throws std::invalid_argument on size mismatches.
  IntegrationStats integrateDepthImage(const Transformation& T_G_C, const DepthImage& depth,
                                       const PinholeCamera& camera, const ColorImage* color);

  const IntegratorConfig& config() const { return config_; }

 private:
  IntegratorConfig config_;
  TsdfLayer* layer_;
  // The blocks of one search cell (pixels [u0, u0 + 8) x [v0, v0 + 8), clipped to the image).
  void collectBlocks(const Eigen::Matrix3f& R_G_C, const Eigen::Vector3f& t_G_C, int u0, int v0,
                     std::vector<uint64_t>* keys);
  // The blocks around the cell's centre ray between depths d_min and d_max.
  struct CellRay;
  void addSegmentBlocks(const CellRay& ray, float d_min, float d_max, std::vector<uint64_t>* keys);

  // The blocks found so far this frame: the cube of blocks around the sensor that holds every
  // block within reach of a valid depth, or, for a segment outside it (or a cube too large),
  // the approximate hash set.
  BlockCubeSet block_cube_;
  ApproxHashSet block_set_;
  int width_ = 0, height_ = 0;
  std::vector<ProjectivePixelSample> samples_;  // per pixel; ray factors for factor_camera_
  // Per 8x8-pixel search cell of the current frame: its deepest valid depth, 0 if none
  // (the table's grid, filled by the search; its levels serve the block screen).
  RectangleMaxTable cell_depth_table_;
  PinholeIntrinsics factor_camera_;
};

}  // namespace cblox
