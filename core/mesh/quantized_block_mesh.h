#pragma once

// A block's mesh in the compact form the mapper streams it in (CBLOX_MESH_UPDATE, voxblox's
// per-block mesh message idea): positions as 16-bit offsets from the block's centre, colours
// as bytes, triangles as 16-bit vertex indices.

#include <array>
#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "core/mesh/mesh.h"

namespace cblox {

/// The quantised mesh of one block of edge `block_size` whose centre is c (block index b:
/// c = (b + 0.5) * block_size). Exact contract:
///   vertex position p = c + q * quantum, quantum = block_size / 32768, q in [-32767, 32767]
///   per axis (so |p - c| < block_size: every vertex a block's cubes can make lies within it,
///   they span the block and one voxel beyond its upper faces);
///   quantizeBlockMesh() rounds to the nearest q (error <= quantum / 2 per axis).
///   colors: empty or one RGB triple per vertex (Color is RGB).
///   triangles: vertex indices in [0, number of vertices), counter-clockwise seen from the
///   positive-SDF side (Mesh's convention); at most kMaxVertices vertices.
/// Value type.
struct QuantizedBlockMesh {
  static constexpr int kMaxVertices = 32767;
  std::vector<std::array<int16_t, 3>> positions;
  std::vector<std::array<uint8_t, 3>> colors;
  std::vector<std::array<int16_t, 3>> triangles;

  bool empty() const { return positions.empty() && triangles.empty(); }
  /// Bytes of the arrays (6 per vertex, 3 per colour, 6 per triangle).
  size_t payloadBytes() const { return positions.size() * 6 + colors.size() * 3 + triangles.size() * 6; }
  /// Empty when the contract's array rules hold, otherwise what breaks them (for a receiver:
  /// colour count, triangle index range, vertex count). Thread-safe.
  std::string validate() const;
  friend bool operator==(const QuantizedBlockMesh&, const QuantizedBlockMesh&) = default;
};

/// The quantum of a block of edge `block_size`: block_size / 32768.
inline double meshQuantum(double block_size) { return block_size / 32768.0; }

/// `mesh_S` (a block's mesh in the layer frame; normals are dropped) into *out. Positions
/// beyond the block's reach are clamped to +-32767 quanta. Returns false with a message when
/// the mesh has more than kMaxVertices vertices or breaks Mesh's invariants (*out cleared).
/// Thread-safe (pure).
bool quantizeBlockMesh(const Mesh& mesh_S, const Eigen::Vector3d& block_center_S,
                       double block_size, QuantizedBlockMesh* out, std::string* error);

/// The mesh `q` stands for, in the layer frame (no normals). Thread-safe (pure).
Mesh dequantizeBlockMesh(const QuantizedBlockMesh& q, const Eigen::Vector3d& block_center_S,
                         double block_size);

}  // namespace cblox
