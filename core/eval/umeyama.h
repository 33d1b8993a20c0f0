#pragma once

#include <optional>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "core/geometry/se3.h"

namespace cblox {

/// A similarity transform from frame B to frame A: p_A = scale * (R_A_B * p_B) + t_A_B, where
/// R_A_B and t_A_B (metres) are the rotation and translation of T_A_B. With scale == 1 it is
/// the rigid transform T_A_B. Plain value type.
struct Alignment {
  Transformationd T_A_B;
  double scale = 1.0;  ///< unitless, > 0

  /// scale * (R_A_B * p_B) + t_A_B. Thread-safe (pure).
  Eigen::Vector3d apply(const Eigen::Vector3d& p_B) const {
    return scale * (T_A_B.rotation() * p_B) + T_A_B.translation();
  }
};

/// Which transform umeyamaAlign() estimates.
enum class AlignmentType {
  kNone,  ///< no alignment: identity, scale 1
  kSE3,   ///< rotation and translation, scale fixed to 1
  kSim3,  ///< rotation, translation and scale
};

/// "none", "se3" or "sim3". Thread-safe.
const char* alignmentTypeName(AlignmentType type);

/// Parses "none", "se3" or "sim3" (lower case, as written by alignmentTypeName()). Returns
/// std::nullopt for anything else. Thread-safe.
std::optional<AlignmentType> parseAlignmentType(const std::string& name);

/// Least-squares alignment of corresponding points (Umeyama, "Least-squares estimation of
/// transformation parameters between two point patterns", PAMI 1991): returns the (R, t, s)
/// minimising sum_i |points_A[i] - (s * R * points_B[i] + t)|^2, so that
/// points_A[i] ~ alignment.apply(points_B[i]). R is always a proper rotation (det +1): when
/// the best orthogonal matrix would be a reflection, the reflection fix of Umeyama's Eq. (39)
/// flips the axis of the smallest singular value of the cross-covariance.
///   - kNone: identity and scale 1; only sizes and finiteness are checked (any count, also 0).
///   - kSE3: s = 1, t = mean_A - R * mean_B.
///   - kSim3: s = trace(D S) / sigma_B^2 (Umeyama's Eq. (42); sigma_B^2 the mean squared
///     distance of points_B from their centroid), t = mean_A - s * R * mean_B. Note that s
///     is the scale that maps B onto A, not a symmetric estimate.
/// For noise-free data related by an exact rigid (kSE3) or similarity (kSim3) transform with
/// non-collinear points, the transform is recovered to rounding. The estimate itself is
/// Eigen::umeyama(); this function adds the checks below. Returns std::nullopt and,
/// when error is non-null, a message when the sizes differ, a coordinate is not finite, or
/// (kSE3 and kSim3 only) there are fewer than 3 points or the configuration is degenerate:
/// the second-largest singular value of the cross-covariance is <= 1e-10 times the largest
/// (all points coincide or lie on one line in either set, so a rotation about that line is
/// undetermined). Coplanar points are fine. Thread-safe (pure).
std::optional<Alignment> umeyamaAlign(const std::vector<Eigen::Vector3d>& points_B,
                                      const std::vector<Eigen::Vector3d>& points_A,
                                      AlignmentType type, std::string* error);

}  // namespace cblox
