#pragma once

// cblox-mapper's mesh stream on LCM: the Mapper's MeshStreamer (core/mapping/mesh_streamer.h)
// publishes its subvolume lists on CBLOX_SUBVOLUMES and its updates on CBLOX_MESH_UPDATE.

#include <atomic>
#include <cstdint>

#include <lcm/lcm-cpp.hpp>

#include "core/mapping/mapper.h"
#include "daemon/common/heartbeat.h"
#include "daemon/mapper/mapper_process_config.h"

namespace cblox {

/// Publishes the mesh stream. Thread-safety: attach() once, before Mapper::start(); the
/// publishing runs on the mapper's worker; addTo() from any thread.
class MeshStreamNode {
 public:
  /// `config` and `lcm` must outlive the node.
  MeshStreamNode(const MapperProcessConfig& config, lcm::LCM* lcm) : config_(config), lcm_(lcm) {}

  /// Gives `mapper` the sinks (Mapper::setMeshStreamSinks); nothing when
  /// mesh_stream.enabled is false.
  void attach(Mapper* mapper);
  /// The stream's counters (status.mesh_stream) and the encoded bytes published.
  void addTo(HeartbeatBuilder* heartbeat, const MeshStreamStats& stats) const;

 private:
  const MapperProcessConfig& config_;
  lcm::LCM* lcm_;
  std::atomic<uint64_t> wire_bytes_{0};  // mesh_update_t bytes as encoded
};

}  // namespace cblox
