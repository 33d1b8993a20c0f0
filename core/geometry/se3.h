#pragma once

#include <cmath>
#include <limits>
#include <ostream>

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <Eigen/SVD>

namespace cblox {

/// Returns the skew-symmetric (cross-product) matrix [v]x, so that skew(a) * b == a.cross(b).
/// Unitless. Thread-safe (pure).
template <typename S>
Eigen::Matrix<S, 3, 3> skew(const Eigen::Matrix<S, 3, 1>& v) {
  Eigen::Matrix<S, 3, 3> m;
  m << S(0), -v.z(), v.y(),  //
      v.z(), S(0), -v.x(),   //
      -v.y(), v.x(), S(0);
  return m;
}

/// Rigid-body transform in SE(3), stored as a unit quaternion and a translation (metres).
///
/// Naming convention: an SE3 called T_A_B maps points expressed in frame B into frame A,
/// p_A = T_A_B * p_B, and transforms compose as T_A_C = T_A_B * T_B_C.
///
/// Value type: all const member functions are thread-safe (no shared state); concurrent
/// mutation of one object needs external synchronisation.
template <typename Scalar>
class SE3 {
 public:
  using Vec3 = Eigen::Matrix<Scalar, 3, 1>;
  using Vec6 = Eigen::Matrix<Scalar, 6, 1>;
  using Mat3 = Eigen::Matrix<Scalar, 3, 3>;
  using Mat4 = Eigen::Matrix<Scalar, 4, 4>;
  using Quat = Eigen::Quaternion<Scalar>;

  /// Identity transform. Thread-safe.
  SE3() : q_(Quat::Identity()), t_(Vec3::Zero()) {}

  /// From a rotation quaternion (normalised here; must be non-zero) and a translation in
  /// metres. Thread-safe.
  SE3(const Quat& q, const Vec3& t) : q_(q.normalized()), t_(t) {}

  /// From a rotation matrix (must already be a rotation; use fromMatrix() to project a noisy
  /// one) and a translation in metres. Thread-safe.
  SE3(const Mat3& R, const Vec3& t) : q_(Quat(R).normalized()), t_(t) {}

  /// Identity transform. Thread-safe.
  static SE3 Identity() { return SE3(); }

  /// From a quaternion that is already unit (as rotation() returns it), kept bit for bit:
  /// normalising it again may change its last bits, so a saved pose would not load
  /// bit-identical. Precondition: |q| = 1 to rounding (the map file readers check it).
  /// Thread-safe.
  static SE3 fromUnitQuaternion(const Quat& q, const Vec3& t) {
    SE3 T;
    T.q_ = q;
    T.t_ = t;
    return T;
  }

  /// From a 4x4 homogeneous matrix [R t; 0 1] (translation in metres). The 3x3 block is
  /// projected onto the nearest rotation in the Frobenius norm (SVD, det = +1); the bottom row
  /// is ignored. Thread-safe.
  static SE3 fromMatrix(const Mat4& T) {
    const Mat3 M = T.template topLeftCorner<3, 3>();
    Eigen::JacobiSVD<Mat3> svd(M, Eigen::ComputeFullU | Eigen::ComputeFullV);
    Mat3 U = svd.matrixU();
    const Mat3 V = svd.matrixV();
    if ((U * V.transpose()).determinant() < Scalar(0)) {
      U.col(2) = -U.col(2);  // flip the axis of the smallest singular value
    }
    return SE3(Mat3(U * V.transpose()), Vec3(T.template topRightCorner<3, 1>()));
  }

  /// Unit quaternion of the rotation. Thread-safe.
  const Quat& rotation() const { return q_; }
  /// 3x3 rotation matrix. Thread-safe.
  Mat3 rotationMatrix() const { return q_.toRotationMatrix(); }
  /// Translation in metres (the origin of the source frame expressed in the target frame).
  /// Thread-safe.
  const Vec3& translation() const { return t_; }
  /// 4x4 homogeneous matrix [R t; 0 0 0 1]. Thread-safe.
  Mat4 matrix() const {
    Mat4 T = Mat4::Identity();
    T.template topLeftCorner<3, 3>() = rotationMatrix();
    T.template topRightCorner<3, 1>() = t_;
    return T;
  }

  /// Composition: T_A_C = T_A_B * T_B_C. The result's quaternion is re-normalised.
  /// Thread-safe.
  SE3 operator*(const SE3& o) const { return SE3(q_ * o.q_, q_ * o.t_ + t_); }

  /// Transforms a point: p_A = T_A_B * p_B (metres). Thread-safe.
  Vec3 operator*(const Vec3& p) const { return q_ * p + t_; }

  /// Inverse: T_B_A = T_A_B.inverse(). Thread-safe.
  SE3 inverse() const {
    const Quat q_inv = q_.conjugate();
    return SE3(q_inv, -(q_inv * t_));
  }

  /// SE(3) exponential. xi = [rho; phi]: rho (metres) is the translational part, phi the
  /// rotation vector (axis * angle, radians). Returns R = exp([phi]x), t = V(phi) * rho with the
  /// left Jacobian V = I + (1 - cos th)/th^2 [phi]x + (th - sin th)/th^3 [phi]x^2. Uses Taylor
  /// series for small angles, so it is exact to rounding at th = 0 and for tiny th.
  /// Thread-safe.
  static SE3 exp(const Vec6& xi) {
    const Vec3 rho = xi.template head<3>();
    const Vec3 phi = xi.template tail<3>();
    const Scalar theta2 = phi.squaredNorm();
    const Scalar theta = std::sqrt(theta2);
    Scalar half_sinc;  // sin(th/2) / th
    Scalar a;          // (1 - cos th) / th^2
    Scalar b;          // (th - sin th) / th^3
    if (theta < smallAngle()) {
      const Scalar theta4 = theta2 * theta2;
      half_sinc = Scalar(0.5) - theta2 / Scalar(48) + theta4 / Scalar(3840);
      a = Scalar(0.5) - theta2 / Scalar(24) + theta4 / Scalar(720);
      b = Scalar(1) / Scalar(6) - theta2 / Scalar(120) + theta4 / Scalar(5040);
    } else {
      const Scalar s_half = std::sin(theta / Scalar(2));
      half_sinc = s_half / theta;
      a = Scalar(2) * s_half * s_half / theta2;  // avoids cancellation in 1 - cos th
      b = (theta - std::sin(theta)) / (theta2 * theta);
    }
    const Quat q(std::cos(theta / Scalar(2)), half_sinc * phi.x(), half_sinc * phi.y(),
                 half_sinc * phi.z());
    const Vec3 phi_x_rho = phi.cross(rho);
    const Vec3 t = rho + a * phi_x_rho + b * phi.cross(phi_x_rho);
    return SE3(q, t);
  }

  /// SE(3) logarithm, the inverse of exp(): returns [rho (metres); phi (radians)] with
  /// |phi| in [0, pi]. Computed from the quaternion (atan2), so it is accurate near 0 and near
  /// pi; at exactly pi the sign of the axis is arbitrary. Thread-safe.
  Vec6 log() const {
    Quat q = q_;
    if (q.w() < Scalar(0)) q.coeffs() = -q.coeffs();  // same rotation, angle in [0, pi]
    const Vec3 v = q.vec();
    const Scalar w = q.w();
    const Scalar n2 = v.squaredNorm();
    const Scalar n = std::sqrt(n2);  // sin(th/2)
    Scalar theta_over_n;
    if (n < smallAngle()) {
      // th = 2 atan(n / w); series of atan(x)/x with x = n/w (w ~ 1 here).
      const Scalar x2 = n2 / (w * w);
      theta_over_n = Scalar(2) / w * (Scalar(1) - x2 / Scalar(3) + x2 * x2 / Scalar(5));
    } else {
      theta_over_n = Scalar(2) * std::atan2(n, w) / n;
    }
    const Vec3 phi = theta_over_n * v;
    const Scalar theta2 = phi.squaredNorm();
    const Scalar theta = std::sqrt(theta2);
    // V^-1 = I - 1/2 [phi]x + c [phi]x^2, c = (1 - (th/2) cot(th/2)) / th^2.
    Scalar c;
    if (theta < smallAngle()) {
      c = Scalar(1) / Scalar(12) + theta2 / Scalar(720) + theta2 * theta2 / Scalar(30240);
    } else {
      // cot(th/2) = w / n for the normalised quaternion with th = 2 atan2(n, w).
      c = (Scalar(1) - Scalar(0.5) * theta * w / n) / theta2;
    }
    const Vec3 phi_x_t = phi.cross(t_);
    Vec6 xi;
    xi.template head<3>() = t_ - Scalar(0.5) * phi_x_t + c * phi.cross(phi_x_t);
    xi.template tail<3>() = phi;
    return xi;
  }

  /// Casts to another scalar type (the quaternion is re-normalised). Thread-safe.
  template <typename T>
  SE3<T> cast() const {
    return SE3<T>(q_.template cast<T>(), t_.template cast<T>());
  }

  /// Geodesic interpolation a * exp(t * log(a^-1 * b)); t in [0, 1] gives a at 0 and b at 1
  /// (other t extrapolate). Constant-velocity screw motion in the frame of a. Thread-safe.
  static SE3 interpolate(const SE3& a, const SE3& b, Scalar t) {
    return a * exp(t * (a.inverse() * b).log());
  }

  /// True if the rotation angle between the two is <= tol (radians) and the translations
  /// differ by <= tol (metres, Euclidean norm). Thread-safe.
  bool isApprox(const SE3& o, Scalar tol) const {
    return q_.angularDistance(o.q_) <= tol && (t_ - o.t_).norm() <= tol;
  }

 private:
  // Below this angle (radians) exp/log use Taylor series: eps^(1/4), ~1.2e-4 for double and
  // ~1.9e-2 for float. The truncated terms are far below rounding there.
  static Scalar smallAngle() {
    return std::sqrt(std::sqrt(std::numeric_limits<Scalar>::epsilon()));
  }

  Quat q_;
  Vec3 t_;
};

/// Prints "SE3(q = [x y z w], t = [x y z])"; for test output and logs. Thread-safe.
template <typename Scalar>
std::ostream& operator<<(std::ostream& os, const SE3<Scalar>& T) {
  const auto& q = T.rotation();
  const auto& t = T.translation();
  return os << "SE3(q = [" << q.x() << ' ' << q.y() << ' ' << q.z() << ' ' << q.w() << "], t = ["
            << t.x() << ' ' << t.y() << ' ' << t.z() << "])";
}

using Transformation = SE3<float>;
using Transformationd = SE3<double>;

}  // namespace cblox
