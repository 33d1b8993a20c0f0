#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>

#include "core/geometry/color.h"
#include "core/geometry/se3.h"
#include "core/mesh/mesh.h"

namespace cblox {

/// Builders of closed (or, for quads, flat) triangle meshes of simple shapes, appended to a
/// mesh with vertex colours. Every builder keeps the mesh's colours consistent (the mesh must
/// be empty or have colours) and adds no normals. Triangles are counter-clockwise seen from
/// the outside (from inside for `inward` boxes), so geometric normals point outwards. Shapes
/// are closed 2-manifolds with shared vertices (every edge in exactly two triangles), except
/// quads (a flat grid with a boundary).
/// Thread-safety: each call mutates only *mesh; not thread-safe for the same mesh.

/// A planar rectangle corner + a * edge_u + b * edge_v, (a, b) in [0, 1]^2, split into
/// cells_u x cells_v cells (>= 1) of two triangles; its normal is edge_u x edge_v.
void appendQuad(Mesh* mesh, const Eigen::Vector3f& corner, const Eigen::Vector3f& edge_u,
                const Eigen::Vector3f& edge_v, const Color& color, int cells_u = 1,
                int cells_v = 1);

/// The surface of `box` (12 triangles, 8 vertices); normals point out of the box, or into it
/// when `inward` (a room seen from inside).
void appendBox(Mesh* mesh, const Eigen::AlignedBox3f& box, const Color& color,
               bool inward = false);

/// A box of half extents `half` (metres) centred at the origin of frame B, placed by T_G_B.
void appendOrientedBox(Mesh* mesh, const Transformation& T_G_B, const Eigen::Vector3f& half,
                       const Color& color);

/// A closed cylinder from `base` to `base + axis` of the given radius, with `segments`
/// (>= 3) sides and flat caps.
void appendCylinder(Mesh* mesh, const Eigen::Vector3f& base, const Eigen::Vector3f& axis,
                    float radius, int segments, const Color& color);

/// A closed cone: disc of `radius` at `base`, apex at `base + axis`, `segments` (>= 3) sides.
void appendCone(Mesh* mesh, const Eigen::Vector3f& base, const Eigen::Vector3f& axis,
                float radius, int segments, const Color& color);

/// A UV sphere with `rings` (>= 2) latitude bands and `segments` (>= 3) longitudes.
void appendSphere(Mesh* mesh, const Eigen::Vector3f& centre, float radius, int rings,
                  int segments, const Color& color);

/// A torus segment (a bent pipe): tube of `tube_radius` around a circle of `bend_radius` in
/// the plane spanned by (u, v) about `centre`, from angle 0 to `angle` radians (a closed ring
/// when angle >= 2 pi), open ends capped. Used for pipe elbows.
void appendPipeBend(Mesh* mesh, const Eigen::Vector3f& centre, const Eigen::Vector3f& u,
                    const Eigen::Vector3f& v, float bend_radius, float tube_radius, float angle,
                    int segments, int tube_segments, const Color& color);

}  // namespace cblox
