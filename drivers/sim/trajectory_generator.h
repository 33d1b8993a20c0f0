#pragma once

#include <optional>
#include <string>
#include <vector>

#include <Eigen/Core>
#include <Eigen/Geometry>

#include "core/io/tum_trajectory.h"

namespace cblox {

/// How a vehicle moves along a path. Plain value type.
struct MotionProfile {
  double speed_mps = 1.0;      ///< cruise speed
  double rate_hz = 20.0;       ///< pose (camera frame) rate
  double accel_time_s = 1.5;   ///< smooth ramp from rest to cruise speed and back
  double turn_radius_m = 1.0;  ///< corners of the waypoint polyline become arcs of this radius
                               ///< (smaller where the segments are short)
  double arc_step_deg = 2.0;   ///< an arc is a polyline of this many degrees a segment, and
                               ///< the camera looks along the segment it is on: the heading
                               ///< turns in steps of this size
  double ease_m = 0.0;         ///< > 0: the path is averaged over this much arc length, so
                               ///< the yaw rate ramps in and out of a turn over it (a car's
                               ///< easement) instead of jumping; 0 = off
  double pitch_down_rad = 0.1; ///< camera tilt below the direction of travel
  double max_bank_rad = 0.15;  ///< roll into turns (a multirotor banks; 0 for a car)
  double bank_per_accel = 0.08;  ///< roll (rad) per m/s^2 of lateral acceleration
  double start_time_s = 0.0;   ///< time stamp of the first pose

  /// Empty when valid, else a message naming the first bad field. Thread-safe.
  std::string validate() const;
};

/// Samples a smooth camera trajectory along the waypoint polyline (world frame, z up): corners
/// are rounded with circular arcs, speed ramps up from rest with a smoothstep over
/// accel_time_s, cruises, and ramps down to rest at the end; poses come at rate_hz. The camera
/// (x right, y down, z forward) looks along the direction of travel, pitched down by
/// pitch_down_rad and banked into turns, or at `look_at` when given (then without bank).
/// A closed path returns to its first waypoint and is flown `laps` times (revisiting places).
/// Throws std::invalid_argument for fewer than 2 waypoints, laps < 1, an invalid profile, or a
/// path of zero length. Thread-safe (pure).
StampedTrajectory followPath(const std::vector<Eigen::Vector3d>& waypoints, bool closed,
                             int laps, const MotionProfile& motion,
                             const std::optional<Eigen::Vector3d>& look_at = std::nullopt);

/// n waypoints on a horizontal circle (closed path).
std::vector<Eigen::Vector3d> orbitWaypoints(const Eigen::Vector3d& centre, double radius,
                                            int n = 48);

/// Back-and-forth lines over the rectangle [min, max] (x, y) at height z, `spacing` apart
/// along y, lines along x (open path).
std::vector<Eigen::Vector3d> lawnMowerWaypoints(const Eigen::Vector2d& min,
                                                const Eigen::Vector2d& max, double z,
                                                double spacing);

/// A figure eight (lemniscate of Gerono) of half length `half_x` and half width `half_y`
/// around centre (closed path, n waypoints).
std::vector<Eigen::Vector3d> figureEightWaypoints(const Eigen::Vector3d& centre, double half_x,
                                                  double half_y, int n = 64);

/// Camera pose at `position` looking along `forward` (world, z up) with the camera's x axis
/// horizontal, then rolled by `roll_rad` about the viewing direction. Throws
/// std::invalid_argument if forward is zero or vertical. Thread-safe (pure).
Transformationd cameraLookingAlong(const Eigen::Vector3d& position, const Eigen::Vector3d& forward,
                                   double roll_rad = 0.0);

}  // namespace cblox
