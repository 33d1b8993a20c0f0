#pragma once

#include <string>

#include <ceres/solver.h>

namespace cblox {

/// Settings shared by the Ceres-based optimisers here (bundle adjustment, pose graph).
struct CeresSolverConfig {
  /// Ceres threads (Jacobian evaluation, Schur elimination / factorisation). >= 1.
  int num_threads = 1;
  /// Wall-clock limit, seconds; 0 = none. Ceres checks it after each iteration, so one
  /// iteration may overrun it. >= 0 and finite.
  double max_time_s = 0.0;
  /// Convergence tolerances (Ceres' defaults; relative, dimensionless). >= 0.
  double function_tolerance = 1e-6;
  double gradient_tolerance = 1e-10;
  double parameter_tolerance = 1e-8;
};

/// Empty if valid, else a message naming the first bad field. Thread-safe (pure).
std::string validate(const CeresSolverConfig& settings);

/// Solver options with these settings, the given iteration limit and time limit (seconds,
/// 0 = none), silent logging. The caller sets the linear solver. Thread-safe (pure).
ceres::Solver::Options solverOptions(const CeresSolverConfig& settings, int max_iterations,
                                     double time_limit_s);

/// The best sparse linear algebra library of this Ceres build (SUITE_SPARSE, else
/// EIGEN_SPARSE, else CX_SPARSE), or NO_SPARSE if it has none. Thread-safe.
ceres::SparseLinearAlgebraLibraryType bestSparseLibrary();

}  // namespace cblox
