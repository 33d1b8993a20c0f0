#pragma once

#include <cstddef>
#include <string>

#include "core/mesh/mesh.h"

namespace cblox {

/// What readObj() read besides the mesh: counts of statements it skipped, so a caller can log
/// that a file carried data (curves, texture coordinates) the mesh does not represent.
struct ObjReadStats {
  size_t vertices = 0;   ///< `v` statements
  size_t faces = 0;      ///< `f` statements (polygons before triangulation)
  size_t triangles = 0;  ///< triangles after fan triangulation
  /// Known statements parsed or skipped without effect on the mesh: vt, vn, vp, o, g, s,
  /// usemtl, mtllib, l, p.
  size_t ignored_statements = 0;
  /// Statements with any other keyword (skipped), e.g. curve and surface statements.
  size_t unknown_statements = 0;
  /// The first unknown keyword and its 1-based line number (empty / 0 when there was none).
  std::string first_unknown_keyword;
  int first_unknown_line = 0;
  /// True when some but not all vertices had colours, so the colours were dropped.
  bool colors_dropped = false;
};

/// Reads a Wavefront OBJ file into `*mesh` (replaced). Understood statements:
/// - `v x y z [w]`: a vertex (w, the rational weight, is checked and ignored), or
///   `v x y z r g b`: a vertex with the common vertex-colour extension. Colours are taken as
///   floats in [0, 1] and scaled by 255, unless some colour value in the file exceeds 1, in
///   which case all colours of the file are taken as 0-255 values; either way they are
///   rounded and clamped to [0, 255]. Colours are kept only when every vertex has them
///   (otherwise dropped and `stats->colors_dropped` is set). Coordinates are parsed as
///   float; "nan" and "inf" are accepted here (Mesh allows them; callers check finiteness).
/// - `f a b c ...`: a polygon of >= 3 corners, each `i`, `i/t`, `i//n` or `i/t/n`. Vertex
///   indices are 1-based; negative ones count back from the last vertex defined so far (-1
///   is the latest). A face may only use vertices defined before it (as every exporter
///   writes them). Texture and normal indices must be non-zero integers but are otherwise
///   ignored. Polygons are triangulated as fans (c0, ci, ci+1), keeping their winding.
/// - `vt`, `vn`: texture coordinates and normals; their numbers are checked (1-3 numbers for
///   vt, 3 for vn) and then ignored (OBJ normals are per face corner, not per vertex).
/// - `vp`, `o`, `g`, `s`, `usemtl`, `mtllib`, `l`, `p`: skipped (counted as ignored).
/// - any other keyword: skipped and counted as unknown (not an error, so files with curves,
///   surfaces or vendor extensions still load their polygons).
/// `#` starts a comment anywhere on a line, blank lines are skipped, a line ending in `\`
/// continues on the next one (errors name the line where the statement starts), keywords are
/// case-sensitive, and CR LF line ends are accepted.
///
/// Returns false with `*error` (when not null) set to "<path>:<line>: <what>" for a malformed
/// known statement: a number that does not parse or is out of float range, a wrong number of
/// values, a vertex index that is 0, out of range or not an integer, a face with fewer than 3
/// corners, a NUL byte (binary data); and to "<path>: <what>" when the file cannot be read.
/// `*mesh` is left unchanged on failure. `stats` (may be null) receives counts on success.
/// Thread-safe (no shared state).
bool readObj(const std::string& path, Mesh* mesh, std::string* error,
             ObjReadStats* stats = nullptr);

/// Writes `mesh` as a Wavefront OBJ file that readObj() reads back exactly: a comment line,
/// then one `v x y z` line per vertex (shortest text that reads back to the same float), as
/// `v x y z r g b` with colours as floats c / 255 in [0, 1] when the mesh has colours (the
/// form MeshLab and Open3D read), then one `f a b c` line per triangle with 1-based indices.
/// Normals are not written (readObj ignores `vn`). Returns false and sets `*error` (when not
/// null) if the mesh violates its invariants (Mesh::validate) or the file cannot be written.
/// Thread-safe (no shared state; concurrent writes to the same path race in the file system).
bool writeObj(const std::string& path, const Mesh& mesh, std::string* error);

}  // namespace cblox
