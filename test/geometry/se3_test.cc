#include "core/geometry/se3.h"
#include "core/geometry/se3_adjoint.h"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <random>
#include <vector>

#include <gtest/gtest.h>

namespace cblox {
namespace {

using Vec3 = Eigen::Vector3d;
using Vec6 = Transformationd::Vec6;
constexpr double kPi = std::numbers::pi;

Vec6 makeXi(const Vec3& rho, const Vec3& phi) {
  Vec6 xi;
  xi << rho, phi;
  return xi;
}

// Deterministic random twists with rotation angle in [0, max_angle].
std::vector<Vec6> randomTwists(int n, double max_angle, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> uni(-1.0, 1.0);
  std::uniform_real_distribution<double> angle(0.0, max_angle);
  std::vector<Vec6> out;
  for (int i = 0; i < n; ++i) {
    Vec3 axis(uni(rng), uni(rng), uni(rng));
    axis.normalize();
    const Vec3 rho(3 * uni(rng), 3 * uni(rng), 3 * uni(rng));
    out.push_back(makeXi(rho, angle(rng) * axis));
  }
  return out;
}

Transformationd randomPose(std::mt19937* rng) {
  std::uniform_real_distribution<double> uni(-1.0, 1.0);
  const Eigen::Quaterniond q(uni(*rng), uni(*rng), uni(*rng), uni(*rng));
  return Transformationd(q, Vec3(5 * uni(*rng), 5 * uni(*rng), 5 * uni(*rng)));
}

// Element-wise |a - b| <= tol. Templated on fixed-size types (a MatrixXd reduction trips a
// GCC 12 -Wmaybe-uninitialized false positive inside the AVX-512 intrinsics at -march=native).
template <typename A, typename B>
void expectMatNear(const Eigen::MatrixBase<A>& a_expr, const Eigen::MatrixBase<B>& b_expr,
                   double tol) {
  const auto a = a_expr.eval();
  const auto b = b_expr.eval();
  ASSERT_EQ(a.rows(), b.rows());
  ASSERT_EQ(a.cols(), b.cols());
  double max_err = 0.0;
  for (Eigen::Index i = 0; i < a.rows(); ++i) {
    for (Eigen::Index j = 0; j < a.cols(); ++j) {
      max_err =
          std::max(max_err, std::abs(static_cast<double>(a(i, j)) - static_cast<double>(b(i, j))));
    }
  }
  EXPECT_LE(max_err, tol) << "a =\n" << a << "\nb =\n" << b;
}

TEST(Skew, MatchesCrossProduct) {
  const Vec3 a(1.0, -2.0, 3.5);
  const Vec3 b(-0.5, 4.0, 2.0);
  expectMatNear(skew(a) * b, a.cross(b), 1e-15);
  expectMatNear(skew(a).transpose(), -skew(a), 0.0);
}

TEST(SE3, DefaultIsIdentity) {
  const Transformationd T;
  expectMatNear(T.matrix(), Eigen::Matrix4d::Identity(), 0.0);
  const Vec3 p(1, 2, 3);
  expectMatNear(T * p, p, 0.0);
}

TEST(SE3, QuaternionConstructorNormalises) {
  const Transformationd T(Eigen::Quaterniond(2.0, 0.0, 0.0, 0.0), Vec3(1, 2, 3));
  EXPECT_DOUBLE_EQ(T.rotation().norm(), 1.0);
  expectMatNear(T.rotationMatrix(), Eigen::Matrix3d::Identity(), 1e-15);
  const Eigen::Quaterniond q_raw(1.0, 2.0, -1.0, 0.5);
  const Transformationd T2(q_raw, Vec3::Zero());
  EXPECT_NEAR(T2.rotation().norm(), 1.0, 1e-15);
  expectMatNear(T2.rotationMatrix(), q_raw.normalized().toRotationMatrix(), 1e-15);
}

TEST(SE3, MatrixConstructorAndAccessors) {
  const Eigen::Matrix3d R = Eigen::AngleAxisd(0.7, Vec3(1, 2, 3).normalized()).toRotationMatrix();
  const Vec3 t(0.5, -1.0, 2.0);
  const Transformationd T(R, t);
  expectMatNear(T.rotationMatrix(), R, 1e-15);
  expectMatNear(T.translation(), t, 0.0);
  Eigen::Matrix4d M = Eigen::Matrix4d::Identity();
  M.topLeftCorner<3, 3>() = R;
  M.topRightCorner<3, 1>() = t;
  expectMatNear(T.matrix(), M, 1e-15);
  const Vec3 p(0.3, 0.2, -0.1);
  expectMatNear(T * p, R * p + t, 1e-15);
}

TEST(SE3, ExpOfZeroIsIdentityAndLogOfIdentityIsZero) {
  const Transformationd T = Transformationd::exp(Vec6::Zero());
  EXPECT_EQ(T.rotation().w(), 1.0);
  EXPECT_EQ(T.rotation().vec(), Vec3::Zero());
  EXPECT_EQ(T.translation(), Vec3::Zero());
  EXPECT_EQ(Transformationd().log(), Vec6::Zero());
}

TEST(SE3, ExpOfPureTranslation) {
  const Vec3 rho(1.5, -2.0, 0.25);
  const Transformationd T = Transformationd::exp(makeXi(rho, Vec3::Zero()));
  expectMatNear(T.translation(), rho, 0.0);
  expectMatNear(T.rotationMatrix(), Eigen::Matrix3d::Identity(), 0.0);
}

TEST(SE3, ExpOfPureRotationEqualsAngleAxis) {
  for (const Vec6& xi : randomTwists(50, kPi, 1)) {
    const Vec3 phi = xi.tail<3>();
    const Transformationd T = Transformationd::exp(makeXi(Vec3::Zero(), phi));
    const Eigen::Matrix3d expected =
        Eigen::AngleAxisd(phi.norm(), phi.normalized()).toRotationMatrix();
    expectMatNear(T.rotationMatrix(), expected, 1e-14);
    expectMatNear(T.translation(), Vec3::Zero(), 0.0);
  }
}

TEST(SE3, ExpOfScrewAboutZMatchesHandComputedLeftJacobian) {
  // phi = (0, 0, pi/2), rho = (1, 0, 0):
  // V rho = rho + (1 - cos th)/th^2 phi x rho + (th - sin th)/th^3 phi x (phi x rho)
  //       = (1, 0, 0) + (4/pi^2)(0, pi/2, 0) + ((pi/2 - 1) 8/pi^3)(-pi^2/4, 0, 0)
  //       = (2/pi, 2/pi, 0).
  const Transformationd T = Transformationd::exp(makeXi(Vec3(1, 0, 0), Vec3(0, 0, kPi / 2)));
  expectMatNear(T.translation(), Vec3(2 / kPi, 2 / kPi, 0), 1e-15);
  expectMatNear(T.rotationMatrix(), Eigen::AngleAxisd(kPi / 2, Vec3::UnitZ()).toRotationMatrix(),
                1e-15);
}

TEST(SE3, ExpLogRoundTripRandom) {
  for (const Vec6& xi : randomTwists(500, kPi - 1e-6, 2)) {
    const Transformationd T = Transformationd::exp(xi);
    expectMatNear(T.log(), xi, 1e-12);
  }
}

TEST(SE3, LogExpRoundTripRandomPoses) {
  std::mt19937 rng(3);
  for (int i = 0; i < 500; ++i) {
    const Transformationd T = randomPose(&rng);
    const Vec6 xi = T.log();
    EXPECT_LE(xi.tail<3>().norm(), kPi + 1e-15);
    EXPECT_TRUE(Transformationd::exp(xi).isApprox(T, 1e-12)) << T;
  }
}

// T exp(xi) T^-1 == exp(Ad(T) xi) for random poses and twists (any size: the identity is
// exact, not first order), and Ad of a composition is the product of the adjoints.
TEST(SE3, AdjointConjugatesTheExponential) {
  std::mt19937 rng(4);
  const std::vector<Vec6> twists = randomTwists(200, kPi - 1e-3, 5);
  for (const Vec6& xi : twists) {
    const Transformationd T = randomPose(&rng);
    const Transformationd conjugated = T * Transformationd::exp(xi) * T.inverse();
    EXPECT_TRUE(conjugated.isApprox(Transformationd::exp(adjoint(T) * xi), 1e-11))
        << T << " xi " << xi.transpose();
  }
  const Transformationd A = randomPose(&rng), B = randomPose(&rng);
  expectMatNear(adjoint(A * B), adjoint(A) * adjoint(B), 1e-12);
  expectMatNear(adjoint(A.inverse()), adjoint(A).inverse().eval(), 1e-12);
  // A pure translation t: rotations pass unchanged, a rotation phi adds t x phi to rho.
  const Transformationd shift(Eigen::Quaterniond::Identity(), Vec3(1, 2, 3));
  expectMatNear(adjoint(shift) * makeXi(Vec3::Zero(), Vec3(0, 0, 1)),
                makeXi(Vec3(2, -1, 0), Vec3(0, 0, 1)), 1e-15);
}

TEST(SE3, TinyAngle) {
  const Vec3 axis = Vec3(1, -2, 2).normalized();
  const Vec6 xi = makeXi(Vec3(1, 2, 3), 1e-10 * axis);
  const Transformationd T = Transformationd::exp(xi);
  // Rotation: q = (cos(th/2), sin(th/2) axis) ~ (1, 5e-11 axis).
  expectMatNear(T.rotation().vec(), 0.5e-10 * axis, 1e-26);
  expectMatNear(T.rotationMatrix(), Eigen::AngleAxisd(1e-10, axis).toRotationMatrix(), 1e-16);
  // Translation: V ~ I + 1/2 [phi]x.
  const Vec3 expected_t = Vec3(1, 2, 3) + 0.5 * (1e-10 * axis).cross(Vec3(1, 2, 3));
  expectMatNear(T.translation(), expected_t, 1e-15);
  const Vec6 back = T.log();
  expectMatNear(back.tail<3>(), xi.tail<3>(), 1e-25);
  expectMatNear(back.head<3>(), xi.head<3>(), 1e-15);
}

TEST(SE3, SmallAnglesAroundTaylorSwitch) {
  // Angles straddling the Taylor/closed-form switch must round-trip equally well.
  const Vec3 axis = Vec3(0.3, 0.4, -0.5).normalized();
  for (double angle : {1e-8, 1e-6, 1e-5, 1e-4, 1.2e-4, 1.3e-4, 1e-3, 1e-2}) {
    const Vec6 xi = makeXi(Vec3(0.5, -1.0, 2.0), angle * axis);
    const Transformationd T = Transformationd::exp(xi);
    expectMatNear(T.log(), xi, 1e-14);
    expectMatNear(T.rotationMatrix(), Eigen::AngleAxisd(angle, axis).toRotationMatrix(), 1e-15);
  }
}

TEST(SE3, AngleNearPi) {
  const Vec3 axis = Vec3(1, 1, -1).normalized();
  for (double eps : {1e-3, 1e-6, 1e-9}) {
    const Vec6 xi = makeXi(Vec3(0.2, -0.3, 1.0), (kPi - eps) * axis);
    const Transformationd T = Transformationd::exp(xi);
    expectMatNear(T.rotationMatrix(), Eigen::AngleAxisd(kPi - eps, axis).toRotationMatrix(), 1e-14);
    expectMatNear(T.log(), xi, 1e-12);
  }
}

TEST(SE3, AngleExactlyPi) {
  // R = diag(1, -1, -1): rotation by pi about x; the log's axis sign is arbitrary.
  Eigen::Matrix3d R = Eigen::Vector3d(1, -1, -1).asDiagonal();
  const Transformationd T(R, Vec3(1, 2, 3));
  const Vec6 xi = T.log();
  EXPECT_NEAR(std::abs(xi(3)), kPi, 1e-15);
  EXPECT_NEAR(xi(4), 0.0, 1e-15);
  EXPECT_NEAR(xi(5), 0.0, 1e-15);
  EXPECT_TRUE(Transformationd::exp(xi).isApprox(T, 1e-14));
}

TEST(SE3, AngleJustOverPiWrapsToShorterRotation) {
  // Rotation by pi + 0.1 about z is rotation by pi - 0.1 about -z.
  const Transformationd T(Eigen::Quaterniond(Eigen::AngleAxisd(kPi + 0.1, Vec3::UnitZ())),
                          Vec3::Zero());
  const Vec6 xi = T.log();
  expectMatNear(xi, makeXi(Vec3::Zero(), Vec3(0, 0, -(kPi - 0.1))), 1e-14);
}

TEST(SE3, ComposeAndInverseIdentities) {
  std::mt19937 rng(4);
  for (int i = 0; i < 100; ++i) {
    const Transformationd A = randomPose(&rng);
    const Transformationd B = randomPose(&rng);
    const Transformationd C = randomPose(&rng);
    const Vec3 p(0.1 * i, -0.2, 0.3);
    EXPECT_TRUE((A * A.inverse()).isApprox(Transformationd(), 1e-14));
    EXPECT_TRUE((A.inverse() * A).isApprox(Transformationd(), 1e-14));
    EXPECT_TRUE(((A * B) * C).isApprox(A * (B * C), 1e-13));
    EXPECT_TRUE((A * B).inverse().isApprox(B.inverse() * A.inverse(), 1e-13));
    EXPECT_TRUE(A.inverse().inverse().isApprox(A, 1e-14));
    expectMatNear((A * B) * p, A * (B * p), 1e-13);
    expectMatNear(A.inverse() * (A * p), p, 1e-13);
    expectMatNear((A * B).matrix(), A.matrix() * B.matrix(), 1e-13);
    expectMatNear(A.inverse().matrix(), A.matrix().inverse(), 1e-13);
  }
}

TEST(SE3, FrameConvention) {
  // T_W_C: camera at (1, 0, 0) in the world, rotated 90 deg about z. The camera's x axis
  // points along world y.
  const Transformationd T_W_C(Eigen::Quaterniond(Eigen::AngleAxisd(kPi / 2, Vec3::UnitZ())),
                              Vec3(1, 0, 0));
  expectMatNear(T_W_C * Vec3::Zero(), Vec3(1, 0, 0), 1e-15);
  expectMatNear(T_W_C * Vec3(1, 0, 0), Vec3(1, 1, 0), 1e-15);
  // T_C_W maps the world origin into the camera frame.
  expectMatNear(T_W_C.inverse() * Vec3::Zero(), Vec3(0, 1, 0), 1e-15);
}

TEST(SE3, InterpolateEndpoints) {
  std::mt19937 rng(5);
  for (int i = 0; i < 50; ++i) {
    const Transformationd a = randomPose(&rng);
    const Transformationd b = randomPose(&rng);
    EXPECT_TRUE(Transformationd::interpolate(a, b, 0.0).isApprox(a, 1e-14));
    EXPECT_TRUE(Transformationd::interpolate(a, b, 1.0).isApprox(b, 1e-12));
  }
}

TEST(SE3, InterpolateMidpointOfScrewAboutZ) {
  // b = exp([1, 0, 0, 0, 0, pi/2]) has t = (2/pi, 2/pi, 0). The midpoint is
  // exp([0.5, 0, 0, 0, 0, pi/4]): rotation pi/4 about z and, with th = pi/4,
  // t = (sin th / (2 th), (1 - cos th) / (2 th), 0) = (sqrt2/pi, (2 - sqrt2)/pi, 0).
  const Transformationd a;
  const Transformationd b = Transformationd::exp(makeXi(Vec3(1, 0, 0), Vec3(0, 0, kPi / 2)));
  const Transformationd mid = Transformationd::interpolate(a, b, 0.5);
  expectMatNear(mid.rotationMatrix(), Eigen::AngleAxisd(kPi / 4, Vec3::UnitZ()).toRotationMatrix(),
                1e-15);
  const double s2 = std::sqrt(2.0);
  expectMatNear(mid.translation(), Vec3(s2 / kPi, (2 - s2) / kPi, 0), 1e-15);

  // Pure rotation: midpoint of 0 and 90 degrees about z is 45 degrees, no translation.
  const Transformationd rz(Eigen::Quaterniond(Eigen::AngleAxisd(kPi / 2, Vec3::UnitZ())),
                           Vec3::Zero());
  const Transformationd rmid = Transformationd::interpolate(a, rz, 0.5);
  expectMatNear(rmid.rotationMatrix(), Eigen::AngleAxisd(kPi / 4, Vec3::UnitZ()).toRotationMatrix(),
                1e-15);
  expectMatNear(rmid.translation(), Vec3::Zero(), 1e-15);
}

TEST(SE3, InterpolateIsLeftInvariant) {
  std::mt19937 rng(6);
  const Transformationd a = randomPose(&rng);
  const Transformationd b = randomPose(&rng);
  const Transformationd g = randomPose(&rng);
  for (double t : {0.25, 0.5, 0.75}) {
    EXPECT_TRUE(Transformationd::interpolate(g * a, g * b, t)
                    .isApprox(g * Transformationd::interpolate(a, b, t), 1e-12));
  }
}

TEST(SE3, FromMatrixExactRotation) {
  const Eigen::Matrix3d R =
      Eigen::AngleAxisd(1.2, Vec3(-1, 2, 0.5).normalized()).toRotationMatrix();
  Eigen::Matrix4d M = Eigen::Matrix4d::Identity();
  M.topLeftCorner<3, 3>() = R;
  M.topRightCorner<3, 1>() = Vec3(4, 5, 6);
  const Transformationd T = Transformationd::fromMatrix(M);
  expectMatNear(T.matrix(), M, 1e-14);
}

TEST(SE3, FromMatrixProjectsToNearestRotation) {
  const Eigen::Matrix3d R = Eigen::AngleAxisd(0.8, Vec3(1, 1, 0).normalized()).toRotationMatrix();
  Eigen::Matrix4d M = Eigen::Matrix4d::Identity();
  M.topRightCorner<3, 1>() = Vec3(1, 2, 3);
  // R * S with S symmetric positive definite: polar decomposition gives back exactly R.
  Eigen::Matrix3d S;
  S << 1.1, 0.05, 0.0, 0.05, 0.9, 0.02, 0.0, 0.02, 1.0;
  M.topLeftCorner<3, 3>() = R * S;
  Transformationd T = Transformationd::fromMatrix(M);
  expectMatNear(T.rotationMatrix(), R, 1e-14);
  expectMatNear(T.translation(), Vec3(1, 2, 3), 0.0);
  // A uniformly scaled rotation projects to the rotation.
  M.topLeftCorner<3, 3>() = 2.0 * R;
  T = Transformationd::fromMatrix(M);
  expectMatNear(T.rotationMatrix(), R, 1e-14);
  // A reflection (det < 0) still yields a proper rotation.
  M.topLeftCorner<3, 3>() = R * Eigen::Vector3d(1, 1, -1).asDiagonal();
  T = Transformationd::fromMatrix(M);
  EXPECT_NEAR(T.rotationMatrix().determinant(), 1.0, 1e-14);
  expectMatNear(T.rotationMatrix() * T.rotationMatrix().transpose(), Eigen::Matrix3d::Identity(),
                1e-14);
}

TEST(SE3, Cast) {
  std::mt19937 rng(7);
  const Transformationd Td = randomPose(&rng);
  const Transformation Tf = Td.cast<float>();
  EXPECT_TRUE(Tf.cast<double>().isApprox(Td, 1e-6));
  const Eigen::Vector3f p(0.5f, -0.25f, 2.0f);
  expectMatNear((Tf * p).cast<double>(), Td * p.cast<double>(), 1e-5);
}

TEST(SE3, FloatExpLogRoundTrip) {
  for (const Vec6& xi_d : randomTwists(200, kPi - 1e-2, 8)) {
    const Transformation::Vec6 xi = xi_d.cast<float>();
    const Transformation T = Transformation::exp(xi);
    EXPECT_LE((T.log() - xi).cwiseAbs().maxCoeff(), 1e-5f) << xi.transpose();
  }
  const Transformation::Vec6 tiny = (Transformation::Vec6() << 1, 2, 3, 1e-10f, 0, 0).finished();
  EXPECT_LE((Transformation::exp(tiny).log() - tiny).cwiseAbs().maxCoeff(), 1e-6f);
}

TEST(SE3, IsApprox) {
  const Transformationd a;
  const Transformationd b(Eigen::Quaterniond(Eigen::AngleAxisd(1e-3, Vec3::UnitX())),
                          Vec3(0, 0, 0));
  EXPECT_TRUE(a.isApprox(b, 1.1e-3));
  EXPECT_FALSE(a.isApprox(b, 0.9e-3));
  const Transformationd c(Eigen::Quaterniond::Identity(), Vec3(0, 2e-3, 0));
  EXPECT_TRUE(a.isApprox(c, 2.1e-3));
  EXPECT_FALSE(a.isApprox(c, 1.9e-3));
  // q and -q are the same rotation.
  const Eigen::Quaterniond q(Eigen::AngleAxisd(0.5, Vec3::UnitY()));
  const Transformationd d(q, Vec3::Zero());
  const Transformationd e(Eigen::Quaterniond(-q.coeffs()), Vec3::Zero());
  EXPECT_TRUE(d.isApprox(e, 1e-15));
}

}  // namespace
}  // namespace cblox
