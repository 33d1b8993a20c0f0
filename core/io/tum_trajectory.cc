#include "core/io/tum_trajectory.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <sstream>

namespace cblox {
namespace {

std::string at(const std::string& path, size_t line) {
  return path + ":" + std::to_string(line) + ": ";
}

void setError(std::string* error, std::string message) {
  if (error != nullptr) *error = std::move(message);
}

}  // namespace

std::optional<StampedTrajectory> readTumTrajectory(const std::string& path, std::string* error) {
  std::ifstream in(path);
  if (!in) {
    setError(error, path + ": cannot open trajectory file");
    return std::nullopt;
  }
  StampedTrajectory trajectory;
  std::string text;
  size_t line_number = 0;
  while (std::getline(in, text)) {
    ++line_number;
    std::replace(text.begin(), text.end(), ',', ' ');
    std::replace(text.begin(), text.end(), '\t', ' ');
    const size_t first = text.find_first_not_of(" \r");
    if (first == std::string::npos || text[first] == '#') continue;
    std::istringstream fields(text);
    std::vector<double> values;
    std::string token;
    while (fields >> token) {
      if (token == "\r") continue;
      char* end = nullptr;
      const double value = std::strtod(token.c_str(), &end);
      if (end == token.c_str() || (*end != '\0' && *end != '\r')) {
        setError(error, at(path, line_number) + "'" + token + "' is not a number");
        return std::nullopt;
      }
      if (!std::isfinite(value)) {
        setError(error, at(path, line_number) + "value '" + token + "' is not finite");
        return std::nullopt;
      }
      values.push_back(value);
    }
    if (values.size() != 8) {
      setError(error, at(path, line_number) + "expected 8 numbers (t tx ty tz qx qy qz qw), got " +
                          std::to_string(values.size()));
      return std::nullopt;
    }
    const Eigen::Quaterniond q(values[7], values[4], values[5], values[6]);
    const double norm = q.norm();
    if (std::abs(norm - 1.0) > 1e-3) {
      setError(error, at(path, line_number) + "quaternion norm is " + std::to_string(norm) +
                          ", not 1 (within 1e-3)");
      return std::nullopt;
    }
    if (!trajectory.empty() && values[0] <= trajectory.back().timestamp_s) {
      char buffer[160];
      std::snprintf(buffer, sizeof(buffer), "time %.9f does not increase (previous %.9f)",
                    values[0], trajectory.back().timestamp_s);
      setError(error, at(path, line_number) + buffer);
      return std::nullopt;
    }
    trajectory.push_back(
        {values[0], Transformationd(q.normalized(), Eigen::Vector3d(values[1], values[2], values[3]))});
  }
  if (trajectory.empty()) {
    setError(error, path + ": no pose in trajectory file");
    return std::nullopt;
  }
  return trajectory;
}

bool writeTumTrajectory(const std::string& path, const StampedTrajectory& trajectory,
                        std::string* error) {
  std::FILE* file = std::fopen(path.c_str(), "w");
  if (file == nullptr) {
    setError(error, path + ": cannot open for writing");
    return false;
  }
  std::fprintf(file, "# timestamp tx ty tz qx qy qz qw\n");
  for (const StampedPose& pose : trajectory) {
    const Eigen::Vector3d& t = pose.T_G_C.translation();
    const Eigen::Quaterniond& q = pose.T_G_C.rotation();
    std::fprintf(file, "%.9f %.12g %.12g %.12g %.12g %.12g %.12g %.12g\n", pose.timestamp_s,
                 t.x(), t.y(), t.z(), q.x(), q.y(), q.z(), q.w());
  }
  const bool ok = std::fflush(file) == 0 && std::ferror(file) == 0;
  if (std::fclose(file) != 0 || !ok) {
    setError(error, path + ": write failed");
    return false;
  }
  return true;
}

std::optional<Transformationd> interpolatePose(const StampedTrajectory& trajectory, double t,
                                               double max_gap_s, double tolerance_s) {
  if (trajectory.empty() || !std::isfinite(t)) return std::nullopt;
  if (t <= trajectory.front().timestamp_s) {
    if (trajectory.front().timestamp_s - t > tolerance_s) return std::nullopt;
    return trajectory.front().T_G_C;
  }
  if (t >= trajectory.back().timestamp_s) {
    if (t - trajectory.back().timestamp_s > tolerance_s) return std::nullopt;
    return trajectory.back().T_G_C;
  }
  const auto after = std::upper_bound(
      trajectory.begin(), trajectory.end(), t,
      [](double time, const StampedPose& pose) { return time < pose.timestamp_s; });
  const auto before = after - 1;
  const double gap = after->timestamp_s - before->timestamp_s;
  if (gap > max_gap_s) return std::nullopt;
  const double alpha = (t - before->timestamp_s) / gap;
  return Transformationd::interpolate(before->T_G_C, after->T_G_C, alpha);
}

}  // namespace cblox
