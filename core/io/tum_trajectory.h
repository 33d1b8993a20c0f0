#pragma once

#include <optional>
#include <string>
#include <vector>

#include "core/geometry/se3.h"

namespace cblox {

/// A pose with a time stamp: T_G_C maps points in the camera (or body) frame C into the
/// trajectory's reference frame G. Plain value type.
struct StampedPose {
  double timestamp_s = 0.0;  ///< seconds (any epoch; TUM files use Unix time)
  Transformationd T_G_C;
};

/// Time-ordered poses. Plain value type.
using StampedTrajectory = std::vector<StampedPose>;

/// Reads a trajectory in the TUM RGB-D format: one pose per line, `t tx ty tz qx qy qz qw`
/// (seconds, metres, unit quaternion with the scalar last), separated by spaces, tabs or
/// commas; empty lines and lines starting with '#' are skipped. Returns std::nullopt and,
/// when error is non-null, a message "<path>:<line>: <what>" when the file cannot be opened,
/// a line does not hold exactly 8 numbers, a value is not finite, the quaternion's norm is
/// not within 1e-3 of 1 (it is renormalised when it is), or time does not strictly increase.
/// An empty file (no pose) is an error too. Thread-safe (no shared state).
std::optional<StampedTrajectory> readTumTrajectory(const std::string& path, std::string* error);

/// Writes `trajectory` in the TUM format read by readTumTrajectory(), with a '#' header line,
/// timestamps with 9 decimals and poses with enough digits to read back within 1e-9. Returns
/// false with a message naming the path when the file cannot be written. Thread-safe.
bool writeTumTrajectory(const std::string& path, const StampedTrajectory& trajectory,
                        std::string* error);

/// Pose at time t by geodesic interpolation between the two poses around it (SE3::interpolate).
/// Returns std::nullopt when the trajectory is empty, t is outside [front, back] by more than
/// `tolerance_s`, or the gap between the two neighbours exceeds `max_gap_s` (pass infinity to
/// allow any gap). Inside the tolerance at either end the end pose is returned. The
/// trajectory must be sorted by time. Thread-safe (pure).
std::optional<Transformationd> interpolatePose(const StampedTrajectory& trajectory, double t,
                                               double max_gap_s, double tolerance_s = 0.0);

}  // namespace cblox
