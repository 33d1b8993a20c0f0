#pragma once

#include <string>

#include "core/mesh/mesh.h"

namespace cblox {

/// Encoding of the PLY body.
enum class PlyFormat { kBinaryLittleEndian, kAscii };

/// Writes `mesh` as a PLY file readable by MeshLab and Open3D: element vertex with float
/// x y z, then float nx ny nz when the mesh has normals, then uchar red green blue when it
/// has colours; element face with `property list uchar int vertex_indices` (always present;
/// `element face 0` for a point cloud). ASCII floats use the shortest text that reads back
/// to the same float. Returns false and sets `*error` (when not null) if the mesh violates
/// its invariants (Mesh::validate) or the file cannot be written. Thread-safe (no shared
/// state; concurrent writes to the same path race in the file system).
bool writePly(const std::string& path, const Mesh& mesh, PlyFormat format, std::string* error);

/// Reads a PLY file (format ascii, binary_little_endian or binary_big_endian) into `*mesh`
/// (replaced). Vertex properties may have any PLY scalar type (char/int8, uchar/uint8,
/// short/int16, ushort/uint16, int/int32, uint/uint32, float/float32, double/float64), in any
/// order; x y z are required, nx ny nz and red green blue are picked up when all three are
/// present, everything else (and every other element) is skipped. Integer colours are
/// clamped to [0, 255]; floating-point colours are taken as [0, 1] and scaled. Faces come
/// from the list property `vertex_indices` (or `vertex_index`) with any integer count and
/// index types; polygons are triangulated as fans (v0, vi, vi+1). On a malformed or truncated
/// file, an out-of-range index or an unsupported feature it returns false with a message
/// naming the file, the header line or element and what was expected; it never crashes.
/// Thread-safe (no shared state).
bool readPly(const std::string& path, Mesh* mesh, std::string* error);

}  // namespace cblox
