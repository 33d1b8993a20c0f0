#include "drivers/sim/trajectory_generator.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace cblox {
namespace {

constexpr double kPi = 3.14159265358979323846;

/// The waypoint polyline with rounded corners, as a dense polyline (about 2 cm / 2 degrees).
std::vector<Eigen::Vector3d> roundedPolyline(const std::vector<Eigen::Vector3d>& w, bool closed,
                                             double radius, double arc_step_deg) {
  std::vector<Eigen::Vector3d> points;
  const size_t n = w.size();
  auto add_line = [&](const Eigen::Vector3d& from, const Eigen::Vector3d& to) {
    const int steps = std::max(1, static_cast<int>(std::ceil((to - from).norm() / 0.02)));
    for (int k = points.empty() ? 0 : 1; k <= steps; ++k) {
      points.push_back(from + (to - from) * (static_cast<double>(k) / steps));
    }
  };
  // Corner i has its fillet from entry[i] to exit[i].
  std::vector<Eigen::Vector3d> entry(n), exit(n);
  std::vector<std::vector<Eigen::Vector3d>> arcs(n);
  for (size_t i = 0; i < n; ++i) {
    entry[i] = exit[i] = w[i];
    const bool has_corner = closed || (i > 0 && i + 1 < n);
    if (!has_corner) continue;
    const Eigen::Vector3d& prev = w[(i + n - 1) % n];
    const Eigen::Vector3d& next = w[(i + 1) % n];
    const double len_in = (w[i] - prev).norm(), len_out = (next - w[i]).norm();
    if (len_in <= 0.0 || len_out <= 0.0) continue;
    const Eigen::Vector3d a = (w[i] - prev) / len_in, b = (next - w[i]) / len_out;
    const double turn = std::acos(std::clamp(a.dot(b), -1.0, 1.0));
    if (turn < 1e-6) continue;
    if (turn > kPi - 1e-3) {
      throw std::invalid_argument("followPath: waypoint " + std::to_string(i) +
                                  " reverses the direction of travel");
    }
    double tangent = radius * std::tan(turn / 2.0);
    tangent = std::min(tangent, 0.45 * std::min(len_in, len_out));
    const double r = tangent / std::tan(turn / 2.0);
    entry[i] = w[i] - a * tangent;
    exit[i] = w[i] + b * tangent;
    const Eigen::Vector3d towards_centre = (b - b.dot(a) * a).normalized();
    const Eigen::Vector3d centre = entry[i] + towards_centre * r;
    const int steps = std::max(2, static_cast<int>(std::ceil(turn / (arc_step_deg * kPi / 180.0))));
    const Eigen::Vector3d axis = a.cross(towards_centre);  // rotation axis of the turn
    for (int k = 1; k < steps; ++k) {
      const Eigen::AngleAxisd rotation(turn * k / steps, axis);
      arcs[i].push_back(centre + rotation * (entry[i] - centre));
    }
  }
  const size_t segments = closed ? n : n - 1;
  for (size_t i = 0; i < segments; ++i) {
    const size_t j = (i + 1) % n;
    if (i == 0) {
      points.push_back(exit[0]);
    }
    add_line(exit[i], entry[j]);
    if (j != 0 || closed) {
      for (const Eigen::Vector3d& p : arcs[j]) points.push_back(p);
      if (j != 0) points.push_back(exit[j]);
    }
  }
  if (closed) points.push_back(exit[0]);
  // Drop duplicates (zero-length steps) so tangents are defined.
  std::vector<Eigen::Vector3d> unique;
  for (const Eigen::Vector3d& p : points) {
    if (unique.empty() || (p - unique.back()).norm() > 1e-9) unique.push_back(p);
  }
  return unique;
}

/// Distance travelled after time t with a smoothstep ramp of duration ramp to speed v, cruise,
/// and a symmetric ramp down, over a total length L (the profile is scaled when L is short).
struct SpeedProfile {
  double v, ramp, length, cruise_time;

  SpeedProfile(double speed, double accel_time, double total_length)
      : v(speed), ramp(accel_time), length(total_length) {
    // A smoothstep ramp covers v * ramp / 2 metres.
    if (v * ramp > length) ramp = length / v;  // no cruise: ramp up and straight down
    cruise_time = (length - v * ramp) / v;
  }
  double duration() const { return 2.0 * ramp + cruise_time; }
  // Integral of v * smoothstep(t / ramp) from 0 to t, t in [0, ramp].
  double rampDistance(double t) const {
    if (ramp <= 0.0) return 0.0;
    const double x = t / ramp;
    return v * ramp * (x * x * x - 0.5 * x * x * x * x);
  }
  double distance(double t) const {
    if (t <= 0.0) return 0.0;
    if (t >= duration()) return length;
    if (t < ramp) return rampDistance(t);
    if (t < ramp + cruise_time) return v * ramp / 2.0 + v * (t - ramp);
    return length - rampDistance(duration() - t);
  }
};

}  // namespace

std::string MotionProfile::validate() const {
  auto positive = [](double x) { return x > 0.0 && std::isfinite(x); };
  if (!positive(speed_mps)) return "speed_mps must be > 0, got " + std::to_string(speed_mps);
  if (!positive(rate_hz)) return "rate_hz must be > 0, got " + std::to_string(rate_hz);
  if (!(accel_time_s >= 0.0) || !std::isfinite(accel_time_s)) {
    return "accel_time_s must be >= 0, got " + std::to_string(accel_time_s);
  }
  if (!positive(turn_radius_m)) return "turn_radius_m must be > 0, got " + std::to_string(turn_radius_m);
  if (!(ease_m >= 0.0 && ease_m <= 1000.0)) {
    return "ease_m must be in [0, 1000], got " + std::to_string(ease_m);
  }
  if (!(arc_step_deg >= 0.05 && arc_step_deg <= 10.0)) {
    return "arc_step_deg must be in [0.05, 10], got " + std::to_string(arc_step_deg);
  }
  if (!(std::abs(pitch_down_rad) < kPi / 2)) return "pitch_down_rad must be in (-pi/2, pi/2)";
  if (!(max_bank_rad >= 0.0 && max_bank_rad < kPi / 2)) return "max_bank_rad must be in [0, pi/2)";
  if (!(bank_per_accel >= 0.0) || !std::isfinite(bank_per_accel)) return "bank_per_accel must be >= 0";
  if (!std::isfinite(start_time_s)) return "start_time_s must be finite";
  return {};
}

Transformationd cameraLookingAlong(const Eigen::Vector3d& position, const Eigen::Vector3d& forward,
                                   double roll_rad) {
  const double norm = forward.norm();
  if (!(norm > 0.0)) throw std::invalid_argument("cameraLookingAlong: zero viewing direction");
  const Eigen::Vector3d z = forward / norm;
  Eigen::Vector3d x = z.cross(Eigen::Vector3d::UnitZ());
  if (!(x.norm() > 1e-9)) throw std::invalid_argument("cameraLookingAlong: vertical viewing direction");
  x.normalize();
  Eigen::Vector3d y = z.cross(x);  // down
  if (roll_rad != 0.0) {
    const Eigen::AngleAxisd roll(roll_rad, z);
    x = roll * x;
    y = roll * y;
  }
  Eigen::Matrix3d R;
  R.col(0) = x;
  R.col(1) = y;
  R.col(2) = z;
  return Transformationd(R, position);
}

StampedTrajectory followPath(const std::vector<Eigen::Vector3d>& waypoints, bool closed,
                             int laps, const MotionProfile& motion,
                             const std::optional<Eigen::Vector3d>& look_at) {
  if (const std::string problem = motion.validate(); !problem.empty()) {
    throw std::invalid_argument("MotionProfile: " + problem);
  }
  if (waypoints.size() < 2) throw std::invalid_argument("followPath: need at least 2 waypoints");
  if (laps < 1) throw std::invalid_argument("followPath: laps must be >= 1");
  if (!closed && laps != 1) throw std::invalid_argument("followPath: laps > 1 needs a closed path");
  const std::vector<Eigen::Vector3d> lap =
      roundedPolyline(waypoints, closed, motion.turn_radius_m, motion.arc_step_deg);
  std::vector<Eigen::Vector3d> path = lap;
  for (int k = 1; k < laps; ++k) path.insert(path.end(), lap.begin() + 1, lap.end());
  std::vector<double> arc(path.size(), 0.0);
  for (size_t i = 1; i < path.size(); ++i) arc[i] = arc[i - 1] + (path[i] - path[i - 1]).norm();
  if (!(arc.back() > 0.0)) throw std::invalid_argument("followPath: the path has zero length");

  const SpeedProfile profile(motion.speed_mps, motion.accel_time_s, arc.back());
  auto position_at = [&](double s, Eigen::Vector3d* tangent) {
    s = std::clamp(s, 0.0, arc.back());
    size_t i = static_cast<size_t>(std::upper_bound(arc.begin(), arc.end(), s) - arc.begin());
    i = std::clamp<size_t>(i, 1, path.size() - 1);
    const double t = (s - arc[i - 1]) / (arc[i] - arc[i - 1]);
    if (tangent != nullptr) *tangent = (path[i] - path[i - 1]).normalized();
    return Eigen::Vector3d(path[i - 1] + t * (path[i] - path[i - 1]));
  };
  // Direction of travel, averaged over +-5 cm of path so arc/line junctions rotate smoothly.
  auto heading_at = [&](double s) {
    Eigen::Vector3d sum = Eigen::Vector3d::Zero(), tangent;
    for (int k = -2; k <= 2; ++k) {
      position_at(s + 0.025 * k, &tangent);
      sum += tangent;
    }
    return sum.normalized();
  };
  // With ease_m: the path averaged over a window of ease_m of arc length centred on s
  // (narrower within ease_m / 2 of the path's ends, which it keeps), whose direction is the
  // chord across the window: the yaw rate ramps over ease_m.
  // Half the window at s (clamped to the path first, so never negative).
  auto window = [&](double s) { return std::min({0.5 * motion.ease_m, s, arc.back() - s}); };
  auto eased_position = [&](double s) {
    s = std::clamp(s, 0.0, arc.back());
    const double lo = s - window(s), hi = s + window(s);
    constexpr int kSamples = 33;
    Eigen::Vector3d sum = Eigen::Vector3d::Zero();
    for (int k = 0; k < kSamples; ++k) {
      sum += position_at(lo + (hi - lo) * (k + 0.5) / kSamples, nullptr);
    }
    return Eigen::Vector3d(sum / kSamples);
  };
  auto eased_heading = [&](double s) {
    s = std::clamp(s, 0.0, arc.back());
    const double lo = s - window(s), hi = s + window(s);
    const Eigen::Vector3d chord = position_at(hi, nullptr) - position_at(lo, nullptr);
    return chord.norm() > 1e-9 ? Eigen::Vector3d(chord.normalized()) : heading_at(s);
  };
  const bool eased = motion.ease_m > 0.0;

  const int count = static_cast<int>(std::floor(profile.duration() * motion.rate_hz)) + 1;
  StampedTrajectory trajectory;
  trajectory.reserve(static_cast<size_t>(count));
  for (int k = 0; k < count; ++k) {
    const double t = k / motion.rate_hz;
    const double s = profile.distance(t);
    const Eigen::Vector3d p = eased ? eased_position(s) : position_at(s, nullptr);
    Transformationd pose;
    if (look_at.has_value()) {
      pose = cameraLookingAlong(p, *look_at - p);
    } else {
      const Eigen::Vector3d f = eased ? eased_heading(s) : heading_at(s);
      // Lateral acceleration = speed * yaw rate (from the heading change over 0.1 m of path).
      const double ds = 0.05;
      const Eigen::Vector3d f0 = eased ? eased_heading(s - ds) : heading_at(s - ds);
      const Eigen::Vector3d f1 = eased ? eased_heading(s + ds) : heading_at(s + ds);
      const double yaw_rate_per_m =
          std::atan2(f0.x() * f1.y() - f0.y() * f1.x(), f0.head<2>().dot(f1.head<2>())) / (2 * ds);
      const double speed = (profile.distance(t + 0.01) - profile.distance(t - 0.01)) / 0.02;
      const double lateral_accel = speed * speed * yaw_rate_per_m;
      // A left turn (positive yaw rate) banks left: the camera rolls so its right side rises.
      const double bank = std::clamp(motion.bank_per_accel * lateral_accel, -motion.max_bank_rad,
                                     motion.max_bank_rad);
      const double horizontal = f.head<2>().norm();
      const double elevation = std::atan2(f.z(), horizontal) - motion.pitch_down_rad;
      const Eigen::Vector2d h = horizontal > 1e-9 ? Eigen::Vector2d(f.head<2>() / horizontal)
                                                  : Eigen::Vector2d(1.0, 0.0);
      const Eigen::Vector3d forward(h.x() * std::cos(elevation), h.y() * std::cos(elevation),
                                    std::sin(elevation));
      pose = cameraLookingAlong(p, forward, -bank);
    }
    trajectory.push_back({motion.start_time_s + t, pose});
  }
  return trajectory;
}

std::vector<Eigen::Vector3d> orbitWaypoints(const Eigen::Vector3d& centre, double radius, int n) {
  std::vector<Eigen::Vector3d> w;
  for (int i = 0; i < n; ++i) {
    const double a = 2.0 * kPi * i / n;
    w.push_back(centre + radius * Eigen::Vector3d(std::cos(a), std::sin(a), 0.0));
  }
  return w;
}

std::vector<Eigen::Vector3d> lawnMowerWaypoints(const Eigen::Vector2d& min,
                                                const Eigen::Vector2d& max, double z,
                                                double spacing) {
  if (!(spacing > 0.0) || !(max.x() > min.x()) || !(max.y() >= min.y())) {
    throw std::invalid_argument("lawnMowerWaypoints: need max > min and spacing > 0");
  }
  std::vector<Eigen::Vector3d> w;
  bool forward = true;
  for (double y = min.y(); y <= max.y() + 1e-9; y += spacing) {
    const double x0 = forward ? min.x() : max.x(), x1 = forward ? max.x() : min.x();
    w.emplace_back(x0, y, z);
    w.emplace_back(x1, y, z);
    forward = !forward;
  }
  return w;
}

std::vector<Eigen::Vector3d> figureEightWaypoints(const Eigen::Vector3d& centre, double half_x,
                                                  double half_y, int n) {
  std::vector<Eigen::Vector3d> w;
  for (int i = 0; i < n; ++i) {
    const double a = 2.0 * kPi * i / n;
    w.push_back(centre + Eigen::Vector3d(half_x * std::sin(a), half_y * std::sin(2.0 * a), 0.0));
  }
  return w;
}

}  // namespace cblox
