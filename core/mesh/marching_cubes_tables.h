#pragma once

#include <cstdint>

namespace cblox::mc {

// Lookup tables of classic marching cubes (Lorensen & Cline 1987), in the public-domain
// form published by Paul Bourke, "Polygonising a scalar field" (1994),
// http://paulbourke.net/geometry/polygonise/ . All tables are immutable; reading them is
// thread-safe.
//
// Corner numbering (offsets in units of the cube side, from the cube's minimum corner):
//
//          7 ---------- 6          corner  offset (x,y,z)
//         /|           /|            0     (0,0,0)
//        / |          / |            1     (1,0,0)
//       4 ---------- 5  |            2     (1,1,0)
//       |  |         |  |            3     (0,1,0)
//       |  3 --------|- 2            4     (0,0,1)
//       | /          | /             5     (1,0,1)
//       |/           |/              6     (1,1,1)
//       0 ---------- 1               7     (0,1,1)
//     z
//     | y               Edge numbering (edge: corner - corner, axis):
//     |/                  0: 0-1 x    4: 4-5 x    8: 0-4 z
//     +--- x              1: 1-2 y    5: 5-6 y    9: 1-5 z
//                         2: 2-3 x    6: 6-7 x   10: 2-6 z
//                         3: 3-0 y    7: 7-4 y   11: 3-7 z
//
// Configuration index: bit i is set when corner i is inside (SDF < 0).

/// Offset of each corner from the cube's minimum corner, in cube sides.
inline constexpr int kCornerOffsets[8][3] = {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0},
                                             {0, 0, 1}, {1, 0, 1}, {1, 1, 1}, {0, 1, 1}};

/// The two corners joined by each edge, as in Bourke's Polygonise().
inline constexpr int kEdgeCorners[12][2] = {{0, 1}, {1, 2}, {2, 3}, {3, 0}, {4, 5}, {5, 6},
                                            {6, 7}, {7, 4}, {0, 4}, {1, 5}, {2, 6}, {3, 7}};

/// For each edge, its lower corner (the one with the smaller coordinate along the edge) ...
inline constexpr int kEdgeLowerCorner[12] = {0, 1, 3, 0, 4, 5, 7, 4, 0, 1, 2, 3};
/// ... its upper corner ...
inline constexpr int kEdgeUpperCorner[12] = {1, 2, 2, 3, 5, 6, 6, 7, 4, 5, 6, 7};
/// ... and its axis (0 = x, 1 = y, 2 = z).
inline constexpr int kEdgeAxis[12] = {0, 1, 0, 1, 0, 1, 0, 1, 2, 2, 2, 2};

/// kEdgeTable[config]: bit e set when edge e has a zero crossing (its corners differ in
/// inside/outside).
extern const uint16_t kEdgeTable[256];

/// kTriangleTable[config]: up to 5 triangles as triples of edge indices, terminated by -1.
/// As published, each triple is counter-clockwise seen from the *inside* (negative SDF);
/// marching_cubes.cc reverses it so that emitted triangles face the positive side.
extern const int8_t kTriangleTable[256][16];

}  // namespace cblox::mc
