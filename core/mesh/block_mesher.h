#pragma once

// Marching cubes over one block of a TsdfLayer: the unit MeshIntegrator and the mapper's
// mesh stream are built from.

#include <array>
#include <cstddef>
#include <cstdint>
#include <utility>
#include <vector>

#include "core/geometry/color.h"
#include "core/mesh/mesh.h"
#include "core/tsdf/tsdf_layer.h"

namespace cblox {

struct MeshConfig;

/// The 7 lower neighbours of a block (offsets in {-1, 0}^3 minus the origin): exactly the
/// blocks whose cubes can have a corner in the block, so the blocks whose meshes a change of
/// the block can change (besides its own).
inline constexpr std::array<std::array<int, 3>, 7> kMeshLowerNeighbours = {
    {{-1, 0, 0}, {0, -1, 0}, {0, 0, -1}, {-1, -1, 0}, {-1, 0, -1}, {0, -1, -1}, {-1, -1, -1}}};

/// Identity of a voxel-grid edge: global voxel index of its lower corner, and its axis.
struct MeshEdgeKey {
  int32_t x = 0, y = 0, z = 0, axis = 0;
  friend bool operator==(const MeshEdgeKey&, const MeshEdgeKey&) = default;
  template <typename H>
  friend H AbslHashValue(H h, const MeshEdgeKey& k) {
    return H::combine(std::move(h), k.x, k.y, k.z, k.axis);
  }
};

/// Meshes single blocks (MeshIntegrator's class comment states the geometry): the cubes whose
/// minimum corner is one of the block's voxel centres, read from the block and its 7 upper
/// neighbours (offsets in {0, 1}^3) in `layer`, so a block's mesh is a function of those 8
/// blocks' voxels alone, whichever layer holds copies of them. Vertices are in the layer
/// frame; vertices of one grid edge are shared within the block.
/// Thread safety: one instance per thread (it keeps work buffers); reads the layer without
/// synchronisation.
class BlockMesher {
 public:
  /// `config` must be valid (MeshConfig::validate()) and outlive the mesher.
  explicit BlockMesher(const MeshConfig& config) : config_(config) {}

  /// The mesh of `block` (a block of `layer`) into *mesh (cleared first); with `edge_keys`,
  /// the grid edge of every vertex into it (cleared first).
  void meshBlock(const TsdfLayer& layer, const Block& block, Mesh* mesh,
                 std::vector<MeshEdgeKey>* edge_keys = nullptr);

 private:
  const MeshConfig& config_;
  // Voxels of the block and a two-voxel apron on its high sides (from the +x, +y, +z
  // neighbours), i.e. local indices 0 .. n+1 per axis, x fastest.
  std::vector<float> distance_;
  std::vector<uint8_t> valid_;  // weight >= min_weight (0 for missing blocks)
  std::vector<Color> color_;
  // Vertex index per (cube-corner local index 0..n, axis), -1 when none yet.
  std::vector<int> edge_vertex_;
  std::vector<size_t> touched_;
};

}  // namespace cblox
