#pragma once

#include <cstddef>
#include <string>

#include <Eigen/Core>

#include "core/esdf/esdf_config.h"

namespace cblox {

/// Settings of the PlanningService (PlanningConfig::service). Plain value type.
struct PlanningServiceConfig {
  /// Most points one request may carry (the LCM type's MAX_POINTS); more: kTooManyPoints.
  size_t max_points = 4096;
  /// Requests waiting for the worker; one more is answered kBusy at once. >= 1.
  size_t queue_capacity = 16;
  /// Threads that answer one request's points together (PlanningMap::queryBatch): the
  /// query thread and query_threads - 1 helpers it starts per request of at least
  /// PlanningMap::kMinPointsPerThread points each. In [1, 16]. More than 1 pays only with
  /// a core to spare: the reply waits for the slowest helper to be scheduled.
  int query_threads = 1;
  /// A local grid around the vehicle's newest pose every this many seconds; 0 = none.
  /// Finite, >= 0.
  double grid_period_s = 1.0;
  /// The grid's box edge lengths, metres, centred on the vehicle (each finite, > 0).
  Eigen::Vector3d grid_size_m = Eigen::Vector3d(6.0, 6.0, 2.0);
  /// The grid's cell edge, metres (finite, > 0). The box must hold at most
  /// PlanningMap::kMaxGridCells cells.
  double grid_resolution_m = 0.1;

  /// Empty when valid, otherwise a message naming the offending field. Thread-safe.
  std::string validate() const;
};

/// Settings of the mapper's planning map (MapperConfig::planning, planning_map.h). Plain
/// value type.
struct PlanningConfig {
  /// Keep a distance field per subvolume and answer distance queries (Mapper::planningMap).
  /// Off (the default): no field, no memory, Mapper::planningMap() is null. Off by default
  /// while the memory cap's RSS bound is not kept with it on (a 1 cm map's first frames
  /// overshoot the cap, and each block then costs its field too).
  bool enabled = false;
  /// esdf.band_blocks value (the default) that the mapper resolves to 1 band ring when its
  /// integrator carves free space (IntegratorConfig::projective_carving_depth_m > 0), else
  /// to 0 (bandBlocks()).
  static constexpr int kBandAuto = -1;
  /// The fields' settings; band_blocks may be kBandAuto.
  EsdfConfig esdf{.band_blocks = kBandAuto};

  /// esdf.band_blocks, kBandAuto resolved for an integrator carving up to
  /// `carving_depth_m` metres. A subvolume that carved free space can see far past its
  /// neighbours' obstacles, so that only their band bounds its free answers there; without
  /// carving, free space is observed only next to surfaces, where the band hardly changes
  /// an answer but still multiplies the fields' blocks (BENCHMARKS.md).
  int bandBlocks(double carving_depth_m) const {
    if (esdf.band_blocks != kBandAuto) return esdf.band_blocks;
    return carving_depth_m > 0.0 ? 1 : 0;
  }
  /// The fields follow the map every this many seconds, on the fusion/export worker
  /// (PlanningMap::refresh); finite and > 0.
  double refresh_period_s = 0.5;

  /// The distance service for other processes (planning_service.h).
  PlanningServiceConfig service;

  /// Empty when valid, otherwise a message naming the offending field. Thread-safe.
  std::string validate() const;
};

}  // namespace cblox
