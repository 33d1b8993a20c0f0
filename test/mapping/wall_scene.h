#pragma once

// The planning tests' smallest map: one subvolume at the origin of G holding a wall x < 0.31
// (TSDF exact within the 0.15 m truncation) over [-0.4, 1.6] x [-0.4, 0.4]^2, 5 cm voxels,
// 8 per block, its distance field (max 1 m) computed.

#include <memory>

#include "core/mapping/planning_map.h"
#include "core/submap/submap_collection.h"
#include "test/esdf/esdf_test_scenes.h"

namespace cblox::test {

inline constexpr float kWallVoxel = 0.05f;
inline constexpr double kWallX = 0.31;

inline SubmapCollectionConfig wallCollectionConfig() {
  SubmapCollectionConfig c;
  c.layer.voxel_size = kWallVoxel;
  c.layer.voxels_per_side = 8;
  return c;
}

inline EsdfConfig wallFieldConfig() {
  EsdfConfig e;
  e.max_distance_m = 1.0f;
  return e;
}

struct WallScene {
  WallScene() {
    const std::shared_ptr<Submap> wall = collection.createSubmap(Transformationd(), 0, 0);
    esdf_test::writeTsdf(wall->mutableLayer(), esdf_test::planeX(static_cast<float>(kWallX)),
                         Eigen::Vector3f(-0.4f, -0.4f, -0.4f), Eigen::Vector3f(1.6f, 0.4f, 0.4f),
                         0.15f);
    wall->refreshStatistics();
    planning.refresh(collection, PlanningMap::Scope::kAll);
  }
  SubmapCollection collection{wallCollectionConfig()};
  PlanningMap planning{wallFieldConfig()};
};

}  // namespace cblox::test
