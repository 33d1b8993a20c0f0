#pragma once

// Files of the planning map for people and planners (the mapper's commands
// export_distance_grid and export_distance_slice; cblox-ctl grid and esdf-slice).

#include <filesystem>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "core/mapping/mapper_command.h"
#include "core/mapping/planning_map.h"

namespace cblox {

/// Samples `planning` over the box [min_G, max_G] at cell centres `resolution` apart
/// (PlanningMap::localGrid, at most kMaxGridCells) and writes the observed cells as a binary
/// little-endian PLY point cloud to `path`, resolved inside `output_dir` (writableOutputPath):
/// per vertex float x, y, z (the cell centre in G), uchar red, green, blue (occupied black,
/// free coloured by distance / max_distance_m, viridis), float distance (metres, negative
/// inside obstacles), uchar state (1 free, 2 occupied). Unknown cells are not written: a
/// cell of the box that is absent is unknown. The reply says what was written (values path,
/// cells, free, occupied, unknown, seconds) or why nothing was. Thread-safe (PlanningMap's
/// queries are).
MapperReply exportDistanceGrid(const PlanningMap& planning, const Eigen::Vector3d& min_G,
                               const Eigen::Vector3d& max_G, double resolution,
                               const std::filesystem::path& output_dir, const std::string& path);

/// A picture of the planning map at height z_G (a horizontal slice through G): one cell per
/// `resolution` (raised until the slice fits in 1600 x 1600 cells), each drawn as s x s
/// pixels (s in [1, 8], so that the map's longer side takes about 600 pixels or more), over
/// the x, y extent of the fields (PlanningMap::boundsG), x to the right and y up; free space coloured by its
/// distance (viridis, 0 to max_distance_m, with a colour bar in metres), obstacles black,
/// unknown grey; `trajectory_G` (the camera's path, Mapper::trajectoryG) drawn over it as a
/// red line from a white dot. Written as PNG to `path` inside `output_dir`. The reply says
/// what was written (values path, width and height in cells, resolution, free, occupied,
/// unknown, seconds) or why nothing was (an empty map among them). Thread-safe.
MapperReply exportDistanceSlice(const PlanningMap& planning, double z_G, double resolution,
                                const std::vector<Eigen::Vector3d>& trajectory_G,
                                const std::filesystem::path& output_dir, const std::string& path);

}  // namespace cblox
