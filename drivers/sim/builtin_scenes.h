#pragma once

#include <string>
#include <vector>

#include <Eigen/Core>

#include "core/io/tum_trajectory.h"
#include "core/mesh/mesh.h"
#include "drivers/sim/trajectory_generator.h"

namespace cblox {

/// A procedurally generated scene with exact ground truth (its mesh) and the paths a vehicle
/// flies or drives through it. World frame G: z up, metres. Plain value type.
struct BuiltinScene {
  std::string name;
  std::string description;
  Mesh mesh;  ///< vertex-coloured triangles; every solid object is a closed 2-manifold
  /// A closed path that revisits places (what makes loop closure and subvolume fusion matter).
  std::vector<Eigen::Vector3d> loop_waypoints;
  /// A second closed route whose every lap closes two loops (empty if the scene has none):
  /// it drives a small loop, re-enters it (the first closure), leaves it for a wide loop
  /// and re-enters the small loop again from elsewhere (the second, wide-baseline closure),
  /// as the paper's city drives l0 / l1 do.
  std::vector<Eigen::Vector3d> two_loop_waypoints;
  /// A street drive through one sharp turn at car speed (empty if the scene has none): a
  /// straight, a 90-degree corner and a straight, driven once at street_turn_speed_mps with
  /// the corner an arc of street_turn_radius_m (KITTI's sharp turns: about 90 degrees in
  /// 40-50 m at 10-13 m/s).
  std::vector<Eigen::Vector3d> street_turn_waypoints;
  double street_turn_speed_mps = 0.0;
  double street_turn_radius_m = 0.0;
  /// The yaw rate ramps in and out of the corner over this much path (MotionProfile::ease_m).
  double street_turn_ease_m = 0.0;
  /// Orbit: centre of the circle (its z is the flying height) and the point looked at.
  Eigen::Vector3d orbit_centre = Eigen::Vector3d::Zero();
  double orbit_radius = 1.0;
  Eigen::Vector3d orbit_look_at = Eigen::Vector3d::Zero();
  /// Lawn-mower survey: rectangle, height and line spacing.
  Eigen::Vector2d survey_min = Eigen::Vector2d::Zero(), survey_max = Eigen::Vector2d::Ones();
  double survey_height = 1.0;
  double survey_spacing = 1.0;
  /// Figure eight: centre (z = height) and half sizes.
  Eigen::Vector3d eight_centre = Eigen::Vector3d::Zero();
  double eight_half_x = 1.0, eight_half_y = 0.5;
  /// The scene's vehicle: speed, turn radius, bank.
  MotionProfile motion;
  /// Useful depth range for a depth camera in this scene, metres.
  double depth_max_m = 10.0;
  /// Coarsest texture wavelength that looks right at the scene's viewing distances, metres.
  double texture_wavelength_m = 0.4;
};

/// The built-in scene names: "room", "hall", "town" (evaluation scenes) and "yard" (the
/// vocabulary training scene, drivers/sim/training_yard_scene.h).
std::vector<std::string> builtinSceneNames();

/// Builds a scene by name. Throws std::invalid_argument naming the known scenes for an
/// unknown name. Deterministic. Thread-safe (pure).
BuiltinScene makeBuiltinScene(const std::string& name);

/// (a) A living room about the size of ICL-NUIM's (5 x 6.5 x 2.7 m) with sofa, tables,
/// chairs, shelves of books, TV, lamp, plant, pictures and a rug.
BuiltinScene makeLivingRoom();
/// (b) An industrial hall (40 x 20 x 10 m) with columns, pipe racks and elbows, tanks, crates
/// and a mezzanine: the MAV flights of the paper.
BuiltinScene makeIndustrialHall();
/// (c) A small town (about 266 x 266 m): a 4 x 4 street grid 70 m apart lined on both
/// sides with house fronts with windows and roofs, trees; a car-like drive around two blocks that returns to its start.
BuiltinScene makeTown();

/// Trajectory kinds. Every built-in scene provides the first four; kTwoLoops and
/// kStreetTurn only the scenes with two_loop_waypoints / street_turn_waypoints (the town).
enum class TrajectoryKind { kLoop, kOrbit, kLawnMower, kFigureEight, kTwoLoops, kStreetTurn };

/// Parses "loop", "orbit", "lawnmower" / "lawn-mower", "figure-eight" / "figure8",
/// "two-loops", "street-turn". Throws std::invalid_argument naming the accepted values
/// otherwise.
/// Thread-safe.
TrajectoryKind parseTrajectoryKind(const std::string& text);

/// Samples the scene's path of that kind with the scene's motion profile (rate overridden
/// by rate_hz), `laps` times for closed paths (kStreetTurn: once, at its own speed and
/// corner radius). Throws std::invalid_argument for kTwoLoops or kStreetTurn on a scene
/// without that route. Thread-safe (pure).
StampedTrajectory makeSceneTrajectory(const BuiltinScene& scene, TrajectoryKind kind,
                                      double rate_hz, int laps = 1);

}  // namespace cblox
