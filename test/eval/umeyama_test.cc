#include "core/eval/umeyama.h"

#include <cmath>
#include <limits>
#include <random>
#include <string>
#include <vector>

#include <gtest/gtest.h>

namespace cblox {
namespace {

std::vector<Eigen::Vector3d> randomPoints(size_t count, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> uniform(-3.0, 3.0);
  std::vector<Eigen::Vector3d> points;
  for (size_t i = 0; i < count; ++i) points.emplace_back(uniform(rng), uniform(rng), uniform(rng));
  return points;
}

Transformationd knownTransform() {
  Eigen::Matrix<double, 6, 1> xi;
  xi << 1.5, -2.0, 0.7, 0.4, -1.1, 2.3;
  return Transformationd::exp(xi);
}

std::vector<Eigen::Vector3d> transformed(const std::vector<Eigen::Vector3d>& points,
                                         const Transformationd& T, double scale) {
  std::vector<Eigen::Vector3d> out;
  for (const Eigen::Vector3d& p : points)
    out.push_back(scale * (T.rotation() * p) + T.translation());
  return out;
}

TEST(UmeyamaTest, RecoversKnownSE3FromNoiseFreePoints) {
  const auto points_B = randomPoints(20, 1);
  const Transformationd T_A_B = knownTransform();
  std::string error;
  const auto alignment =
      umeyamaAlign(points_B, transformed(points_B, T_A_B, 1.0), AlignmentType::kSE3, &error);
  ASSERT_TRUE(alignment.has_value()) << error;
  EXPECT_TRUE(alignment->T_A_B.isApprox(T_A_B, 1e-9)) << alignment->T_A_B << " vs " << T_A_B;
  EXPECT_EQ(alignment->scale, 1.0);
}

TEST(UmeyamaTest, SE3IgnoresScaleThatSim3Recovers) {
  const auto points_B = randomPoints(15, 2);
  const Transformationd T_A_B = knownTransform();
  const auto points_A = transformed(points_B, T_A_B, 2.5);
  std::string error;
  const auto sim3 = umeyamaAlign(points_B, points_A, AlignmentType::kSim3, &error);
  ASSERT_TRUE(sim3.has_value()) << error;
  EXPECT_NEAR(sim3->scale, 2.5, 1e-9);
  EXPECT_TRUE(sim3->T_A_B.isApprox(T_A_B, 1e-9)) << sim3->T_A_B;
  for (size_t i = 0; i < points_B.size(); ++i) {
    EXPECT_LT((sim3->apply(points_B[i]) - points_A[i]).norm(), 1e-9);
  }
  // SE3 keeps scale 1; the rotation is still right (scaling does not change the SVD's U, V)
  // and t = mean_A - R mean_B.
  const auto se3 = umeyamaAlign(points_B, points_A, AlignmentType::kSE3, &error);
  ASSERT_TRUE(se3.has_value()) << error;
  EXPECT_EQ(se3->scale, 1.0);
  EXPECT_LT(se3->T_A_B.rotation().angularDistance(T_A_B.rotation()), 1e-9);
}

TEST(UmeyamaTest, CoplanarPointsAreFine) {
  std::vector<Eigen::Vector3d> points_B = {{0, 0, 0}, {1, 0, 0}, {0, 2, 0}, {3, 1, 0}};
  const Transformationd T_A_B = knownTransform();
  std::string error;
  const auto alignment =
      umeyamaAlign(points_B, transformed(points_B, T_A_B, 1.0), AlignmentType::kSE3, &error);
  ASSERT_TRUE(alignment.has_value()) << error;
  EXPECT_TRUE(alignment->T_A_B.isApprox(T_A_B, 1e-9)) << alignment->T_A_B;
}

TEST(UmeyamaTest, NoneReturnsIdentity) {
  const auto points_B = randomPoints(5, 3);
  const auto points_A = transformed(points_B, knownTransform(), 3.0);
  std::string error;
  const auto alignment = umeyamaAlign(points_B, points_A, AlignmentType::kNone, &error);
  ASSERT_TRUE(alignment.has_value()) << error;
  EXPECT_TRUE(alignment->T_A_B.isApprox(Transformationd::Identity(), 0.0));
  EXPECT_EQ(alignment->scale, 1.0);
  // kNone needs no minimum count.
  EXPECT_TRUE(umeyamaAlign({}, {}, AlignmentType::kNone, &error).has_value());
}

TEST(UmeyamaTest, ReflectionGivesProperRotation) {
  // points_A is a mirror image of points_B (z flipped): the best orthogonal matrix is a
  // reflection, the best rotation (det +1) is returned instead.
  const auto points_B = randomPoints(30, 4);
  std::vector<Eigen::Vector3d> points_A;
  for (const Eigen::Vector3d& p : points_B) points_A.emplace_back(p.x(), p.y(), -p.z());
  for (const AlignmentType type : {AlignmentType::kSE3, AlignmentType::kSim3}) {
    std::string error;
    const auto alignment = umeyamaAlign(points_B, points_A, type, &error);
    ASSERT_TRUE(alignment.has_value()) << error;
    EXPECT_NEAR(alignment->T_A_B.rotationMatrix().determinant(), 1.0, 1e-12);
    EXPECT_GT(alignment->scale, 0.0);
  }
}

TEST(UmeyamaTest, NoisyFitIsLeastSquaresOptimal) {
  const auto points_B = randomPoints(50, 5);
  auto points_A = transformed(points_B, knownTransform(), 1.7);
  std::mt19937 rng(6);
  std::normal_distribution<double> noise(0.0, 0.05);
  for (Eigen::Vector3d& p : points_A) p += Eigen::Vector3d(noise(rng), noise(rng), noise(rng));
  const auto cost = [&](const Alignment& a) {
    double sum = 0.0;
    for (size_t i = 0; i < points_B.size(); ++i)
      sum += (points_A[i] - a.apply(points_B[i])).squaredNorm();
    return sum;
  };
  for (const AlignmentType type : {AlignmentType::kSE3, AlignmentType::kSim3}) {
    std::string error;
    const auto best = umeyamaAlign(points_B, points_A, type, &error);
    ASSERT_TRUE(best.has_value()) << error;
    const double best_cost = cost(*best);
    // Every small perturbation of the parameters costs more.
    for (int k = 0; k < 7; ++k) {
      for (const double sign : {-1.0, 1.0}) {
        Alignment other = *best;
        if (k < 6) {
          Eigen::Matrix<double, 6, 1> xi = Eigen::Matrix<double, 6, 1>::Zero();
          xi(k) = sign * 1e-4;
          other.T_A_B = Transformationd::exp(xi) * best->T_A_B;
        } else if (type == AlignmentType::kSim3) {
          other.scale *= 1.0 + sign * 1e-4;
        } else {
          continue;
        }
        EXPECT_GT(cost(other), best_cost) << alignmentTypeName(type) << " parameter " << k;
      }
    }
  }
}

TEST(UmeyamaTest, RejectsBadInputWithClearMessages) {
  const auto points = randomPoints(5, 7);
  std::string error;
  EXPECT_FALSE(umeyamaAlign(points, randomPoints(4, 8), AlignmentType::kSE3, &error));
  EXPECT_NE(error.find("differ in size (5 source vs 4 target points)"), std::string::npos) << error;
  EXPECT_FALSE(umeyamaAlign(points, randomPoints(4, 8), AlignmentType::kNone, &error));

  const std::vector<Eigen::Vector3d> two = {{0, 0, 0}, {1, 1, 1}};
  EXPECT_FALSE(umeyamaAlign(two, two, AlignmentType::kSim3, &error));
  EXPECT_NE(error.find("sim3 alignment needs at least 3 point pairs, got 2"), std::string::npos)
      << error;

  std::vector<Eigen::Vector3d> line;
  for (int i = 0; i < 10; ++i) line.emplace_back(0.5 * i, 0.25 * i, -0.1 * i + 2.0);
  EXPECT_FALSE(
      umeyamaAlign(line, transformed(line, knownTransform(), 1.0), AlignmentType::kSE3, &error));
  EXPECT_NE(error.find("degenerate configuration for se3 alignment"), std::string::npos) << error;

  const std::vector<Eigen::Vector3d> same(4, Eigen::Vector3d(1, 2, 3));
  EXPECT_FALSE(umeyamaAlign(same, same, AlignmentType::kSim3, &error));
  EXPECT_NE(error.find("degenerate"), std::string::npos) << error;

  // A non-collinear source mapped onto a line is degenerate too.
  EXPECT_FALSE(umeyamaAlign(randomPoints(10, 9), line, AlignmentType::kSE3, &error));
  EXPECT_NE(error.find("degenerate"), std::string::npos) << error;

  auto bad = points;
  bad[3].y() = std::numeric_limits<double>::quiet_NaN();
  EXPECT_FALSE(umeyamaAlign(points, bad, AlignmentType::kSE3, &error));
  EXPECT_NE(error.find("point 3 is not finite"), std::string::npos) << error;

  EXPECT_FALSE(umeyamaAlign(points, bad, AlignmentType::kSE3, nullptr));  // null error is fine
}

TEST(UmeyamaTest, AlignmentTypeNamesRoundTrip) {
  for (const AlignmentType type :
       {AlignmentType::kNone, AlignmentType::kSE3, AlignmentType::kSim3}) {
    EXPECT_EQ(parseAlignmentType(alignmentTypeName(type)), type);
  }
  EXPECT_FALSE(parseAlignmentType("SE3").has_value());
}

}  // namespace
}  // namespace cblox
