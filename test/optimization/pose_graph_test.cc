#include "core/optimization/pose_graph_optimizer.h"

#include <cmath>
#include <memory>
#include <random>
#include <stdexcept>

#include <gtest/gtest.h>

#include "core/optimization/relative_pose_error.h"
#include "core/optimization/se3_manifold.h"
#include "test/optimization/numeric_diff.h"
#include "test/optimization/synthetic_scenes.h"

namespace cblox {
namespace {

using Mat6 = Eigen::Matrix<double, 6, 6>;

TEST(RelativePoseError, IsZeroForTheTrueRelativePoseAndFollowsTheDefinition) {
  std::mt19937 rng(901);
  const Transformationd A = test::perturbPose(Transformationd(), 3.0, 1.0, rng);
  const Transformationd B = test::perturbPose(Transformationd(), 3.0, 1.0, rng);
  const Transformationd T_i_j = A * B.inverse();  // T_Ci_Cj = T_Ci_G * T_G_Cj
  EXPECT_LT(relativePoseError(T_i_j, A, B).norm(), 1e-14);
  const Transformationd M = test::perturbPose(T_i_j, 0.1, 0.1, rng);
  // With T_i = T_G_Ci: log(M^-1 * T_i^-1 * T_j).
  const Eigen::Matrix<double, 6, 1> e = (M.inverse() * A * B.inverse()).log();
  EXPECT_LT((relativePoseError(M, A, B) - e).norm(), 1e-14);
}

TEST(RelativePoseCost, ResidualAndTangentJacobiansMatchNumericDifferentiation) {
  std::mt19937 rng(911);
  const SE3Manifold manifold;
  Mat6 info = Mat6::Identity();
  info.topLeftCorner<3, 3>() *= 400.0;  // 5 cm sigma
  info(0, 4) = info(4, 0) = 3.0;        // some correlation
  const Mat6 U = sqrtInformation(info);
  EXPECT_LT((U.transpose() * U - info).cwiseAbs().maxCoeff(), 1e-12);
  for (double scale : {0.0, 1e-3, 0.3}) {  // residual size: zero, small angle, large
    const Transformationd A = test::perturbPose(Transformationd(), 2.0, 1.0, rng);
    const Transformationd B = test::perturbPose(Transformationd(), 2.0, 1.0, rng);
    const Transformationd M = test::perturbPose(A * B.inverse(), scale, scale, rng);
    const std::unique_ptr<ceres::CostFunction> cost(newRelativePoseCost(M, U));
    const PoseParameters xa = toPoseParameters(A), xb = toPoseParameters(B);
    Eigen::Matrix<double, 6, 1> r;
    Eigen::Matrix<double, 6, 7, Eigen::RowMajor> Ja, Jb;
    const double* parameters[2] = {xa.data(), xb.data()};
    double* jacobians[2] = {Ja.data(), Jb.data()};
    ASSERT_TRUE(cost->Evaluate(parameters, r.data(), jacobians));
    EXPECT_LT((r - U * relativePoseError(M, A, B)).norm(), 1e-10);
    Eigen::Matrix<double, 7, 6, Eigen::RowMajor> Pa, Pb;
    manifold.PlusJacobian(xa.data(), Pa.data());
    manifold.PlusJacobian(xb.data(), Pb.data());
    for (int which = 0; which < 2; ++which) {
      const Eigen::MatrixXd num = test::numericJacobian(
          [&](const Eigen::VectorXd& d) {
            const Transformationd Ap = which == 0 ? Transformationd::exp(d) * A : A;
            const Transformationd Bp = which == 1 ? Transformationd::exp(d) * B : B;
            return Eigen::VectorXd(U * relativePoseError(M, Ap, Bp));
          },
          Eigen::VectorXd::Zero(6), 1e-7);
      const Eigen::MatrixXd analytic =
          which == 0 ? Eigen::MatrixXd(Ja * Pa) : Eigen::MatrixXd(Jb * Pb);
      EXPECT_LT((num - analytic).cwiseAbs().maxCoeff(), 1e-6 * num.cwiseAbs().maxCoeff())
          << "scale " << scale << " block " << which;
    }
  }
}

// n poses on a circle of radius 5 m, the camera looking at the centre.
std::vector<Transformationd> circle(int n) {
  std::vector<Transformationd> T_C_G;
  for (int k = 0; k < n; ++k) {
    const double a = 2.0 * M_PI * k / n;
    const Eigen::Vector3d c(5.0 * std::cos(a), 0.3 * std::sin(3 * a), 5.0 * std::sin(a));
    // z axis towards the centre, y down.
    const Eigen::Vector3d z = -Eigen::Vector3d(c.x(), 0.0, c.z()).normalized();
    const Eigen::Vector3d y(0, 1, 0);
    Eigen::Matrix3d R_G_C;
    R_G_C << y.cross(z), y, z;
    T_C_G.push_back(Transformationd(R_G_C, c).inverse());
  }
  return T_C_G;
}

struct LoopGraph {
  std::vector<Transformationd> truth;
  std::vector<PoseGraphVertex> vertices;
  std::vector<PoseGraphEdge> edges;
};

// Odometry edges k -> k+1 and the loop edge n-1 -> 0, all measured from the truth; the
// initial poses integrate odometry with a small error per step (drift).
LoopGraph loopGraph(int n, std::uint32_t seed) {
  LoopGraph g;
  g.truth = circle(n);
  std::mt19937 rng(seed);
  for (int k = 0; k < n; ++k) {
    PoseGraphEdge e;
    e.i = k;
    e.j = (k + 1) % n;
    e.T_i_j = g.truth[e.i] * g.truth[e.j].inverse();
    g.edges.push_back(e);
  }
  Transformationd T = g.truth[0];
  for (int k = 0; k < n; ++k) {
    g.vertices.push_back(PoseGraphVertex{static_cast<std::uint64_t>(k), T, k == 0});
    // T_Cj_G = T_i_j^-1 * T_Ci_G, with an error.
    T = test::perturbPose(g.edges[k].T_i_j.inverse(), 0.02, 0.01, rng) * T;
  }
  return g;
}

TEST(PoseGraph, ConsistentLoopWithDriftIsRecoveredExactly) {
  const LoopGraph g = loopGraph(20, 921);
  double start_error = 0.0;
  for (int k = 0; k < 20; ++k) {
    start_error = std::max(start_error, test::poseDistance(g.vertices[k].T_C_G, g.truth[k]));
  }
  ASSERT_GT(start_error, 0.05);
  PoseGraphConfig config;
  config.solver.function_tolerance = config.solver.gradient_tolerance = 1e-16;
  config.solver.parameter_tolerance = 1e-14;
  const PoseGraphResult r = optimizePoseGraph(g.vertices, g.edges, config);
  ASSERT_TRUE(r.success) << r.message;
  for (int k = 0; k < 20; ++k) {
    EXPECT_LT(test::poseDistance(r.T_C_G[k], g.truth[k]), 1e-8) << "vertex " << k;
  }
  EXPECT_LT(r.final_cost, 1e-16);
  EXPECT_GT(r.initial_cost, 1e-3);
  EXPECT_EQ(r.T_C_G[0].translation(), g.vertices[0].T_C_G.translation());  // fixed
  ASSERT_EQ(r.edge_chi2.size(), 20u);
}

TEST(PoseGraph, InconsistentLoopSpreadsTheErrorOverTheLoop) {
  LoopGraph g = loopGraph(20, 931);
  for (int k = 0; k < 20; ++k) g.vertices[k].T_C_G = g.truth[k];
  // The loop edge disagrees with the odometry by 0.4 m along x of C19.
  PoseGraphEdge& loop = g.edges.back();
  const double discrepancy = 0.4;
  loop.T_i_j = Transformationd(Eigen::Quaterniond::Identity(), Eigen::Vector3d(discrepancy, 0, 0)) *
               loop.T_i_j;
  const PoseGraphResult r = optimizePoseGraph(g.vertices, g.edges);
  ASSERT_TRUE(r.success) << r.message;
  // At the start the loop edge holds the whole discrepancy (cost 1/2 * 0.4^2). With unit
  // information the optimum shares it: every edge keeps a few millimetres (translation is
  // cheaper to absorb through small rotations with the 5 m lever arms of the circle), the
  // loop edge under 5%.
  EXPECT_NEAR(r.initial_cost, 0.5 * discrepancy * discrepancy, 1e-12);
  EXPECT_LT(std::sqrt(r.edge_chi2.back()), 0.05 * discrepancy);
  for (size_t e = 0; e < g.edges.size(); ++e) {
    EXPECT_GT(std::sqrt(r.edge_chi2[e]), 0.002 * discrepancy) << "edge " << e;
    EXPECT_LT(std::sqrt(r.edge_chi2[e]), 0.05 * discrepancy) << "edge " << e;
  }
  EXPECT_LT(r.final_cost, 0.01 * r.initial_cost);
  // It is the optimum: moving any free vertex a little raises the cost.
  std::mt19937 rng(932);
  std::vector<PoseGraphVertex> solution = g.vertices;
  for (int k = 0; k < 20; ++k) solution[k].T_C_G = r.T_C_G[k];
  PoseGraphConfig one_step;
  one_step.max_iterations = 1;
  for (int trial = 0; trial < 10; ++trial) {
    std::vector<PoseGraphVertex> moved = solution;
    const int k = 1 + trial;
    moved[k].T_C_G = test::perturbPose(moved[k].T_C_G, 1e-3, 1e-3, rng);
    EXPECT_GT(optimizePoseGraph(moved, g.edges, one_step).initial_cost, r.final_cost);
  }
  // A heavy weight on the odometry instead leaves the loop edge's error almost whole.
  for (size_t e = 0; e + 1 < g.edges.size(); ++e) g.edges[e].information *= 1e6;
  const PoseGraphResult heavy = optimizePoseGraph(g.vertices, g.edges);
  EXPECT_GT(std::sqrt(heavy.edge_chi2.back()), 0.99 * discrepancy);
}

std::string errorOf(std::span<const PoseGraphVertex> v, std::span<const PoseGraphEdge> e,
                    const PoseGraphConfig& c = {}) {
  try {
    optimizePoseGraph(v, e, c);
  } catch (const std::invalid_argument& error) {
    return error.what();
  }
  return "no exception";
}

TEST(PoseGraph, RejectsInvalidInputWithAClearMessage) {
  const LoopGraph g = loopGraph(5, 941);
  EXPECT_EQ(errorOf({}, g.edges), "optimizePoseGraph: no vertices");
  EXPECT_EQ(errorOf(g.vertices, {}), "optimizePoseGraph: no edges");
  std::vector<PoseGraphEdge> edges = g.edges;
  edges[2].j = 5;
  EXPECT_EQ(errorOf(g.vertices, edges),
            "optimizePoseGraph: edge 2: vertex index (2, 5) out of range [0, 5)");
  edges = g.edges;
  edges[1].j = 1;
  EXPECT_EQ(errorOf(g.vertices, edges), "optimizePoseGraph: edge 1: i == j");
  edges = g.edges;
  edges[3].information(2, 2) = -1.0;
  EXPECT_EQ(errorOf(g.vertices, edges),
            "optimizePoseGraph: edge 3: sqrtInformation: the information matrix is not positive "
            "definite");
  edges = g.edges;
  edges[0].information(0, 1) = 0.5;
  EXPECT_EQ(errorOf(g.vertices, edges),
            "optimizePoseGraph: edge 0: sqrtInformation: the information matrix is not "
            "symmetric");
  std::vector<PoseGraphVertex> vertices = g.vertices;
  vertices[4].T_C_G =
      Transformationd(Eigen::Quaterniond::Identity(), Eigen::Vector3d(0, std::nan(""), 0));
  EXPECT_EQ(errorOf(vertices, g.edges), "optimizePoseGraph: vertex 4: T_C_G not finite");
  PoseGraphConfig config;
  config.max_iterations = 0;
  EXPECT_EQ(errorOf(g.vertices, g.edges, config),
            "optimizePoseGraph: config: max_iterations must be >= 1");
}

}  // namespace
}  // namespace cblox
