#pragma once

#include <cstddef>
#include <cstdint>
#include <string>
#include <utility>
#include <vector>

#include <absl/container/flat_hash_map.h>
#include <Eigen/Core>

#include "core/mesh/block_mesher.h"
#include "core/mesh/mesh.h"
#include "core/tsdf/tsdf_layer.h"

namespace cblox {

/// Settings of the marching-cubes mesher.
struct MeshConfig {
  /// Voxels with a lower fusion weight count as unobserved; a cube with such a corner is not
  /// meshed. Must be finite and > 0 (so that missing blocks, weight 0, are never meshed).
  float min_weight = 1e-4f;
  /// Interpolate voxel colours onto the vertices (Mesh::colors).
  bool use_color = true;
  /// Per-vertex normals from the TSDF gradient: central differences at the edge's two corner
  /// voxels, interpolated to the vertex and normalised. Where the central stencil would
  /// leave the block's readable region (its lower faces) or meets an unobserved voxel, the
  /// second-order one-sided difference is used (also O(h^2)), so that a block's mesh depends
  /// only on its own voxels and those of its +x, +y, +z neighbours.
  bool compute_normals = true;
  /// Worker threads for update() (the calling thread is one of them); >= 1. The result does
  /// not depend on it.
  int num_threads = 2;

  /// Empty when valid, otherwise a message naming the offending field. Thread-safe.
  std::string validate() const;
};

/// Incremental marching-cubes mesher of one TsdfLayer, keeping one mesh per block.
///
/// The cubes of a block are those whose minimum corner is one of its voxel centres; they
/// span that block's voxels and those of its +x, +y, +z neighbours. A cube is meshed only
/// when all 8 corner voxels exist and have weight >= min_weight. Vertices lie at the linear
/// zero crossing of each crossed voxel-grid edge, computed from global voxel indices so that
/// every block computes bit-identical positions (and colours) for a shared edge. A block's
/// mesh depends only on the voxels of the block and of its 7 upper neighbours (offsets in
/// {0, 1}^3), so re-meshing an updated block and its 7 lower neighbours reproduces a full
/// re-mesh exactly. Within a block mesh, vertices of one grid edge are shared;
/// extractMesh(true) also merges them across blocks (keeping the first block's normal,
/// in block-key order, for the few edges on block faces whose normal stencils differ).
///
/// Thread safety: not thread-safe; one thread drives an instance. update() reads the layer
/// (and clears Block::updated flags) and must not run concurrently with anything that
/// modifies the layer (integration, fusion, block allocation/removal); run it between
/// integrations. The layer must outlive the mesher.
class MeshIntegrator {
 public:
  /// Throws std::invalid_argument with MeshConfig::validate()'s message when invalid.
  MeshIntegrator(const TsdfLayer& layer, MeshConfig config);

  /// Re-meshes the blocks whose Block::updated() is set, plus the blocks that share cubes
  /// with them (an updated block B also dirties its 7 lower neighbours B-x, B-y, B-z, B-x-y,
  /// B-x-z, B-y-z, B-x-y-z) and the lower neighbours of blocks that left the layer. With
  /// only_updated_blocks = false every block of the layer is re-meshed. Meshes of blocks no
  /// longer in the layer are removed. Clears the updated flags of the blocks it consumed when
  /// clear_updated_flags. Returns the number of blocks re-meshed. See the class comment for
  /// thread safety.
  size_t update(bool only_updated_blocks = true, bool clear_updated_flags = true);

  /// One mesh per meshed block (possibly empty), keyed by packGridIndex(block index), in
  /// the layer frame. Not thread-safe against update().
  const absl::flat_hash_map<uint64_t, Mesh>& blockMeshes() const { return meshes_; }

  /// All block meshes concatenated in block-key order (deterministic). With connected =
  /// true, vertices on the same voxel-grid edge (key: global voxel index of the edge's lower
  /// corner + axis) are merged exactly, so a closed surface yields a watertight indexed mesh.
  /// Not thread-safe against update().
  Mesh extractMesh(bool connected) const;

  /// Drops all block meshes. Not thread-safe against other calls.
  void clear();

  const MeshConfig& config() const { return config_; }

  /// Identity of a voxel-grid edge (block_mesher.h).
  using EdgeKey = MeshEdgeKey;

 private:
  const TsdfLayer& layer_;
  MeshConfig config_;
  absl::flat_hash_map<uint64_t, Mesh> meshes_;
  absl::flat_hash_map<uint64_t, std::vector<EdgeKey>> edge_keys_;
};

}  // namespace cblox
