#include "core/optimization/ceres_solver_config.h"

#include <cmath>

namespace cblox {

std::string validate(const CeresSolverConfig& s) {
  if (s.num_threads < 1) return "num_threads must be >= 1";
  if (!(s.max_time_s >= 0) || !std::isfinite(s.max_time_s)) {
    return "max_time_s must be >= 0 and finite";
  }
  if (!(s.function_tolerance >= 0) || !(s.gradient_tolerance >= 0) ||
      !(s.parameter_tolerance >= 0)) {
    return "tolerances must be >= 0";
  }
  return {};
}

ceres::Solver::Options solverOptions(const CeresSolverConfig& settings, int max_iterations,
                                     double time_limit_s) {
  ceres::Solver::Options options;
  options.max_num_iterations = max_iterations;
  if (time_limit_s > 0.0) options.max_solver_time_in_seconds = time_limit_s;
  options.num_threads = settings.num_threads;
  options.function_tolerance = settings.function_tolerance;
  options.gradient_tolerance = settings.gradient_tolerance;
  options.parameter_tolerance = settings.parameter_tolerance;
  options.logging_type = ceres::SILENT;
  options.minimizer_progress_to_stdout = false;
  return options;
}

ceres::SparseLinearAlgebraLibraryType bestSparseLibrary() {
  for (const auto library : {ceres::SUITE_SPARSE, ceres::EIGEN_SPARSE, ceres::CX_SPARSE}) {
    if (ceres::IsSparseLinearAlgebraLibraryTypeAvailable(library)) return library;
  }
  return ceres::NO_SPARSE;
}

}  // namespace cblox
