#pragma once

#include <string>

#include <Eigen/Core>

namespace cblox {

/// Radial-tangential (Brown-Conrady) coefficients in OpenCV's order and meaning.
struct RadTanCoefficients {
  double k1 = 0, k2 = 0, p1 = 0, p2 = 0, k3 = 0;
};

/// Returns an empty string if all coefficients are finite, else a message naming the first
/// bad one ("k2 must be finite, got nan"). Thread-safe (pure).
std::string validate(const RadTanCoefficients& coefficients);

/// OpenCV's radial-tangential lens distortion acting on normalised image coordinates
/// (x, y) = (X/Z, Y/Z) in the camera frame (unitless):
///   r2 = x^2 + y^2,  radial = 1 + k1 r2 + k2 r2^2 + k3 r2^3
///   x' = x radial + 2 p1 x y + p2 (r2 + 2 x^2)
///   y' = y radial + p1 (r2 + 2 y^2) + 2 p2 x y
/// Immutable after construction: all member functions are thread-safe.
class RadTanDistortion {
 public:
  /// Throws std::invalid_argument with validate()'s message if a coefficient is not finite.
  explicit RadTanDistortion(RadTanCoefficients coefficients);

  /// The coefficients this model was built with. Thread-safe.
  const RadTanCoefficients& coefficients() const { return c_; }

  /// Applies the distortion: undistorted normalised xn -> distorted normalised coordinates.
  /// Thread-safe.
  Eigen::Vector2d distort(const Eigen::Vector2d& xn) const;

  /// Inverts distort() by Gauss-Newton (Newton on the 2x2 system) with the analytic Jacobian,
  /// starting from xd. Converged when |distort(xn) - xd| <= tolerance (normalised units).
  /// Returns false if not converged within max_iterations steps, or on a singular Jacobian or
  /// non-finite values; *xn then holds the last iterate. xn must be non-null. Thread-safe.
  bool undistort(const Eigen::Vector2d& xd, Eigen::Vector2d* xn, int max_iterations = 20,
                 double tolerance = 1e-12) const;

  /// Jacobian d distort(xn) / d xn (2x2, rows = x', y'; columns = x, y). Thread-safe.
  Eigen::Matrix2d jacobian(const Eigen::Vector2d& xn) const;

 private:
  RadTanCoefficients c_;
};

}  // namespace cblox
