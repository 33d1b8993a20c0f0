#include "core/optimization/pose_graph_optimizer.h"

#include <chrono>
#include <memory>
#include <stdexcept>

#include <ceres/ceres.h>

#include "core/optimization/relative_pose_error.h"
#include "core/optimization/se3_manifold.h"

namespace cblox {
namespace {

bool poseFinite(const Transformationd& T) {
  return T.rotation().coeffs().allFinite() && T.translation().allFinite();
}

std::string edgeError(size_t e, const std::string& message) {
  return "optimizePoseGraph: edge " + std::to_string(e) + ": " + message;
}

// Checks the input; returns the sqrt information of every edge.
std::vector<Eigen::Matrix<double, 6, 6>> checkInput(std::span<const PoseGraphVertex> vertices,
                                                    std::span<const PoseGraphEdge> edges,
                                                    const PoseGraphConfig& config) {
  if (const std::string e = validate(config); !e.empty()) {
    throw std::invalid_argument("optimizePoseGraph: config: " + e);
  }
  if (vertices.empty()) throw std::invalid_argument("optimizePoseGraph: no vertices");
  if (edges.empty()) throw std::invalid_argument("optimizePoseGraph: no edges");
  for (size_t v = 0; v < vertices.size(); ++v) {
    if (!poseFinite(vertices[v].T_C_G)) {
      throw std::invalid_argument("optimizePoseGraph: vertex " + std::to_string(v) +
                                  ": T_C_G not finite");
    }
  }
  const auto n = static_cast<int>(vertices.size());
  std::vector<Eigen::Matrix<double, 6, 6>> sqrt_info;
  sqrt_info.reserve(edges.size());
  for (size_t e = 0; e < edges.size(); ++e) {
    const PoseGraphEdge& edge = edges[e];
    if (edge.i < 0 || edge.i >= n || edge.j < 0 || edge.j >= n) {
      throw std::invalid_argument(edgeError(e, "vertex index (" + std::to_string(edge.i) + ", " +
                                                   std::to_string(edge.j) + ") out of range [0, " +
                                                   std::to_string(n) + ")"));
    }
    if (edge.i == edge.j) throw std::invalid_argument(edgeError(e, "i == j"));
    if (!poseFinite(edge.T_i_j)) throw std::invalid_argument(edgeError(e, "T_i_j not finite"));
    try {
      sqrt_info.push_back(sqrtInformation(edge.information));
    } catch (const std::invalid_argument& error) {
      throw std::invalid_argument(edgeError(e, error.what()));
    }
  }
  return sqrt_info;
}

}  // namespace

std::string validate(const PoseGraphConfig& c) {
  if (c.max_iterations < 1) return "max_iterations must be >= 1";
  if (!(c.huber_delta >= 0) || !std::isfinite(c.huber_delta)) {
    return "huber_delta must be >= 0 and finite";
  }
  if (const std::string e = validate(c.solver); !e.empty()) return "solver: " + e;
  return {};
}

PoseGraphResult optimizePoseGraph(std::span<const PoseGraphVertex> vertices,
                                  std::span<const PoseGraphEdge> edges,
                                  const PoseGraphConfig& config) {
  const auto start = std::chrono::steady_clock::now();
  const std::vector<Eigen::Matrix<double, 6, 6>> sqrt_info = checkInput(vertices, edges, config);

  std::vector<PoseParameters> poses;
  poses.reserve(vertices.size());
  for (const PoseGraphVertex& v : vertices) poses.push_back(toPoseParameters(v.T_C_G));

  SE3Manifold manifold;
  std::unique_ptr<ceres::LossFunction> loss;
  if (config.huber_delta > 0.0) loss = std::make_unique<ceres::HuberLoss>(config.huber_delta);
  ceres::Problem::Options problem_options;
  problem_options.loss_function_ownership = ceres::DO_NOT_TAKE_OWNERSHIP;
  problem_options.manifold_ownership = ceres::DO_NOT_TAKE_OWNERSHIP;
  ceres::Problem problem(problem_options);
  std::vector<std::uint8_t> used(vertices.size(), 0);
  for (size_t e = 0; e < edges.size(); ++e) {
    const PoseGraphEdge& edge = edges[e];
    problem.AddResidualBlock(newRelativePoseCost(edge.T_i_j, sqrt_info[e]), loss.get(),
                             poses[edge.i].data(), poses[edge.j].data());
    used[edge.i] = used[edge.j] = 1;
  }
  for (size_t v = 0; v < vertices.size(); ++v) {
    if (!used[v]) continue;
    if (vertices[v].fixed) {
      problem.SetParameterBlockConstant(poses[v].data());
    } else {
      problem.SetManifold(poses[v].data(), &manifold);
    }
  }

  ceres::Solver::Options options =
      solverOptions(config.solver, config.max_iterations, config.solver.max_time_s);
  options.sparse_linear_algebra_library_type = bestSparseLibrary();
  options.linear_solver_type = options.sparse_linear_algebra_library_type == ceres::NO_SPARSE
                                   ? ceres::DENSE_QR
                                   : ceres::SPARSE_NORMAL_CHOLESKY;
  ceres::Solver::Summary summary;
  ceres::Solve(options, &problem, &summary);

  PoseGraphResult result;
  result.initial_cost = summary.initial_cost;
  result.final_cost = summary.final_cost;
  result.iterations = summary.num_successful_steps + summary.num_unsuccessful_steps;
  if (!summary.IsSolutionUsable()) {
    result.success = false;
    result.message = "Ceres: " + summary.message;
  }
  result.T_C_G.reserve(vertices.size());
  for (size_t v = 0; v < vertices.size(); ++v) {
    result.T_C_G.push_back(vertices[v].fixed ? vertices[v].T_C_G
                                             : fromPoseParameters(poses[v].data()));
  }
  result.edge_chi2.reserve(edges.size());
  for (const PoseGraphEdge& edge : edges) {
    const Eigen::Matrix<double, 6, 1> e =
        relativePoseError(edge.T_i_j, result.T_C_G[edge.i], result.T_C_G[edge.j]);
    result.edge_chi2.push_back(e.dot(edge.information * e));
  }
  result.time_ms =
      std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
  return result;
}

}  // namespace cblox
