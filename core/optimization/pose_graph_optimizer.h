#pragma once

#include <cstdint>
#include <span>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "core/geometry/se3.h"
#include "core/optimization/ceres_solver_config.h"

namespace cblox {

/// SE(3) pose-graph optimisation with Ceres, for loop closing (ORB-SLAM2's
/// OptimizeEssentialGraph on the essential graph: spanning tree + strong covisibility edges +
/// loop edges; SE(3) because stereo fixes the scale).
///
/// Vertices hold world-to-camera poses T_C_G (7 doubles with SE3Manifold: left
/// perturbation, tangent [rho (m); phi (rad)]). An edge (i, j) measures T_i_j = T_Ci_Cj
/// (maps points of Cj into Ci; from the current estimates, T_Ci_G * T_Cj_G^-1) and
/// contributes the residual U * e with
///   e = log(T_i_j^-1 * T_Ci_G * T_Cj_G^-1) = log(T_ij_measured^-1 * T_i^-1 * T_j),
/// T_i = T_G_Ci (see relative_pose_error.h), U^T U = information. Ceres' cost is
/// 1/2 sum_edges e^T information e (or rho of it with the Huber loss).
/// Linear solver: SPARSE_NORMAL_CHOLESKY with SuiteSparse (DENSE_QR if Ceres has no sparse
/// library). Fix at least one vertex (gauge); with none the solution is defined up to a rigid
/// motion and only LM's damping keeps it near the start.

struct PoseGraphVertex {
  std::uint64_t id = 0;   ///< caller's keyframe id (reported back, not interpreted)
  Transformationd T_C_G;  ///< initial world-to-camera pose
  bool fixed = false;     ///< held constant
};

struct PoseGraphEdge {
  int i = 0;              ///< index into the vertices
  int j = 0;              ///< index into the vertices (!= i)
  Transformationd T_i_j;  ///< measured T_Ci_Cj
  /// Information of e (symmetric positive definite; units 1/m^2 for rho, 1/rad^2 for phi).
  /// For a scalar weight w use w * Identity.
  Eigen::Matrix<double, 6, 6> information = Eigen::Matrix<double, 6, 6>::Identity();
};

struct PoseGraphConfig {
  /// Ceres LM iterations (ORB-SLAM2's essential graph: 20). >= 1.
  int max_iterations = 20;
  /// Huber delta on sqrt(e^T information e); 0 = no robust loss (ORB-SLAM2). >= 0.
  double huber_delta = 0.0;
  /// Threads, time limit and tolerances of Ceres.
  CeresSolverConfig solver;
};

/// Empty if valid, else a message naming the first bad field. Thread-safe (pure).
std::string validate(const PoseGraphConfig& config);

struct PoseGraphResult {
  /// Optimised poses, one per vertex (fixed and unconnected ones unchanged).
  std::vector<Transformationd> T_C_G;
  /// e^T information e per edge at the solution (dimensionless).
  std::vector<double> edge_chi2;
  /// Ceres cost at the start and at the end (1/2 sum of rho(edge chi2)).
  double initial_cost = 0.0;
  double final_cost = 0.0;
  /// Ceres iterations (successful + unsuccessful steps).
  int iterations = 0;
  double time_ms = 0.0;
  /// False if Ceres reported an unusable solution (`message` says why).
  bool success = true;
  std::string message;
};

/// Optimises the vertex poses. Throws std::invalid_argument with a clear message if there
/// are no vertices or no edges, an edge index is out of range or i == j, a pose is not
/// finite, an information matrix is not symmetric positive definite, or the config is
/// invalid. Thread-safe (no shared state); runs on the calling thread plus
/// config.solver.num_threads - 1 Ceres workers.
PoseGraphResult optimizePoseGraph(std::span<const PoseGraphVertex> vertices,
                                  std::span<const PoseGraphEdge> edges,
                                  const PoseGraphConfig& config = {});

}  // namespace cblox
