#pragma once

#include <vector>

#include <Eigen/Core>

#include "core/geometry/se3.h"
#include "drivers/synthetic/analytic_scene.h"

namespace cblox {

// Ready-made analytic scenes and camera trajectories. The global frame G has z up.
// All functions are thread-safe (pure).

/// A solid sphere of radius 0.5 m centred at the origin, resting on a ground plane z = -0.5
/// (normal +z, touching the sphere at its bottom point). Both checkered (0.1 m cells on the
/// sphere, 0.25 m on the ground).
AnalyticScene makeSphereScene();

/// A single infinite plane through `point` with normal `normal` (normalised; the free side is
/// the one it points to), checkered with cells of `cell_size` metres (<= 0: plain colour).
/// Throws std::invalid_argument for a zero or non-finite normal.
AnalyticScene makePlaneScene(const Eigen::Vector3d& point, const Eigen::Vector3d& normal,
                             double cell_size = 0.25);

/// A 6 x 4 x 3 m room seen from inside: x in [-3, 3], y in [-2, 2], floor z = 0, ceiling
/// z = 3 (one checkered inside box, 0.5 m cells). Furnished with a table (a 1.2 x 0.8 x
/// 0.05 m top at z 0.72..0.77 on four 5 cm square legs, centred at (1, 0.5)), a sphere of
/// radius 0.3 m resting on the floor at (-1, -0.8), and a floor-to-ceiling cylindrical pillar
/// of radius 0.2 m at (-1.8, 1.2). Primitives only touch, they do not overlap, so
/// signedDistance is exact everywhere in free space.
AnalyticScene makeDemoRoom();

/// num_frames camera poses T_G_C evenly spaced on a horizontal circle of `radius` around
/// `centre` at height centre.z() + height, starting at angle 0 (+x) and turning
/// counter-clockwise seen from above (the last pose is one step short of the first). Each
/// camera's z axis points at look_at, its x axis is horizontal and its y axis points as far
/// down (-z in G) as possible. num_frames <= 0 gives an empty vector. Throws
/// std::invalid_argument if a camera would sit on look_at or look straight up or down.
std::vector<Transformationd> makeOrbitTrajectory(const Eigen::Vector3d& centre, double radius,
                                                 double height, int num_frames,
                                                 const Eigen::Vector3d& look_at);

/// The pose T_G_C of a camera at position_G whose z axis points at look_at_G, x axis is
/// horizontal and y axis points as far down as possible. Throws std::invalid_argument if the
/// viewing direction is zero or vertical.
Transformationd lookAt(const Eigen::Vector3d& position_G, const Eigen::Vector3d& look_at_G);

}  // namespace cblox
