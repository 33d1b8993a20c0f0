#pragma once

// What the mapper's mesh stream publishes (mesh_streamer.h) and a receiver applies
// (mesh_mirror.h): the changed blocks' meshes in their subvolume's frame, and the subvolume
// list with the poses that place them. The LCM types mesh_update_t / subvolume_list_t carry
// them field for field.

#include <cstddef>
#include <cstdint>
#include <vector>

#include <Eigen/Core>

#include "core/geometry/se3.h"
#include "core/mesh/quantized_block_mesh.h"
#include "core/submap/submap.h"
#include "core/tsdf/block_index.h"

namespace cblox {

/// The mesh of one block of one subvolume, in the subvolume's frame S (block `index` covers
/// [index, index + 1) * block_size of S). An empty mesh: the block has no surface now; a
/// receiver drops what it holds of it. Value type.
struct MeshBlockUpdate {
  SubmapId submap = -1;
  BlockIndex index = BlockIndex::Zero();
  QuantizedBlockMesh mesh;
};

/// One message of the stream. Value type.
struct MeshUpdate {
  int64_t map_epoch = 0;  ///< Mapper::mapEpoch(); a new one: receivers drop everything
  int64_t sequence = 0;   ///< 1, 2, 3, ... per message since start; a gap: a lost message
  /// This message begins a full refresh: a receiver drops every block it holds first.
  bool refresh_start = false;
  /// Blocks the per-period budget held back after this message (at most this many follow
  /// in later periods); 0: a receiver that applied every message has the map as meshed.
  size_t blocks_pending = 0;
  float block_size = 0.0f;              ///< metres
  std::vector<SubmapId> removed_submaps;  ///< gone (fused, removed): drop all their blocks
  std::vector<MeshBlockUpdate> blocks;

  /// Mesh bytes (QuantizedBlockMesh::payloadBytes summed).
  size_t payloadBytes() const;
};

/// One subvolume as the stream shows it. Value type.
struct SubvolumeView {
  SubmapId id = -1;
  Transformationd T_G_S;  ///< pose of the subvolume frame S in G
  bool active = false;
  KeyframeId anchor_keyframe = -1;
  size_t num_blocks = 0;  ///< allocated TSDF blocks
  /// Axis-aligned bounds of the allocated blocks in S, metres; both zero with no blocks.
  Eigen::Vector3f min_S = Eigen::Vector3f::Zero(), max_S = Eigen::Vector3f::Zero();
};

/// Every subvolume of the map with its pose, published with every update period. Value type.
struct SubvolumeList {
  int64_t map_epoch = 0;
  SubmapId active_submap = -1;  ///< -1: none
  float block_size = 0.0f;
  std::vector<SubvolumeView> subvolumes;  ///< ascending id
};

}  // namespace cblox
