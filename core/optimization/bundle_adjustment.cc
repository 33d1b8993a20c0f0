#include "core/optimization/bundle_adjustment.h"

#include <chrono>
#include <optional>
#include <memory>
#include <sstream>
#include <stdexcept>

#include <ceres/ceres.h>

#include "core/optimization/schur_lm.h"
#include "core/optimization/se3_manifold.h"

namespace cblox {
namespace {

using Clock = std::chrono::steady_clock;

// Mutable copy of the unknowns; Ceres' parameter blocks point into it.
struct BaState {
  std::vector<PoseParameters> poses;
  std::vector<Eigen::Vector3d> points;
};

// Shared, stateless objects that the problems of both passes reference.
struct BaModel {
  SE3Manifold manifold;
  ceres::HuberLoss huber_stereo;
  ceres::HuberLoss huber_mono;
  explicit BaModel(const BundleAdjustmentConfig& c)
      : huber_stereo(c.huber_delta_stereo), huber_mono(c.huber_delta_mono) {}
};

class AbortCallback final : public ceres::IterationCallback {
 public:
  AbortCallback(const std::atomic<bool>* abort, bool* raised) : abort_(abort), raised_(raised) {}
  ceres::CallbackReturnType operator()(const ceres::IterationSummary&) override {
    if (abort_->load(std::memory_order_relaxed)) {
      *raised_ = true;
      return ceres::SOLVER_TERMINATE_SUCCESSFULLY;  // keeps the current iterate
    }
    return ceres::SOLVER_CONTINUE;
  }

 private:
  const std::atomic<bool>* abort_;
  bool* raised_;
};

double observationChi2(const BundleAdjustmentProblem& problem, const BaState& state,
                       const BaObservation& o) {
  const Transformationd T_C_G = fromPoseParameters(state.poses[o.keyframe].data());
  return reprojectionChi2(problem.camera, o, T_C_G * state.points[o.landmark]);
}

// Inlier test of ORB-SLAM2 (false for points behind the camera: chi2 = inf).
bool isInlier(const BundleAdjustmentConfig& config, const BaObservation& o, double chi2) {
  return chi2 <= (o.dimension() == 3 ? config.chi2_stereo : config.chi2_mono);
}

ceres::LinearSolverType linearSolverType(const BundleAdjustmentConfig& config,
                                         int num_free_keyframes) {
  const bool has_sparse = bestSparseLibrary() != ceres::NO_SPARSE;
  switch (config.linear_solver) {
    case BaLinearSolver::kDenseSchur:
      return ceres::DENSE_SCHUR;
    case BaLinearSolver::kSparseSchur:
      return has_sparse ? ceres::SPARSE_SCHUR : ceres::DENSE_SCHUR;
    case BaLinearSolver::kIterativeSchur:
      return ceres::ITERATIVE_SCHUR;
    case BaLinearSolver::kAuto:
    case BaLinearSolver::kNativeDenseSchur:  // not Ceres solvers: solvePass takes them first
    case BaLinearSolver::kNativeSparseSchur:
      break;
  }
  return num_free_keyframes <= config.dense_schur_max_free_keyframes || !has_sparse
             ? ceres::DENSE_SCHUR
             : ceres::SPARSE_SCHUR;
}

struct PassOutcome {
  bool solved = false;  // false if there was nothing to optimise
  bool usable = true;
  double initial_cost = 0.0;
  double final_cost = 0.0;
  int iterations = 0;  // successful + unsuccessful steps
  std::string message;
};

// The free keyframes that some active observation sees.
int countFreeKeyframes(const BundleAdjustmentProblem& problem,
                       const std::vector<std::uint8_t>& active) {
  std::vector<std::uint8_t> seen(problem.keyframes.size(), 0);
  int free = 0;
  for (size_t i = 0; i < problem.observations.size(); ++i) {
    const auto k = static_cast<size_t>(problem.observations[i].keyframe);
    if (!active[i] || seen[k] || problem.keyframes[k].fixed) continue;
    seen[k] = 1;
    ++free;
  }
  return free;
}

// One pass by schurLevenbergMarquardt (schur_lm.h).
PassOutcome solveNativePass(const BundleAdjustmentProblem& problem,
                            const std::vector<std::uint8_t>& active, ReducedMatrix reduced_matrix,
                            bool robust, int iterations, double time_limit_s,
                            const BundleAdjustmentConfig& config, const BaModel& model,
                            BaState* state, const std::atomic<bool>* abort, bool* aborted,
                            std::string* solver_name) {
  SchurLmOptions options;
  options.reduced_matrix = reduced_matrix;
  options.max_iterations = iterations;
  options.time_limit_s = time_limit_s;
  if (robust) {
    options.loss_mono = &model.huber_mono;
    options.loss_stereo = &model.huber_stereo;
  }
  options.function_tolerance = config.solver.function_tolerance;
  options.gradient_tolerance = config.solver.gradient_tolerance;
  options.parameter_tolerance = config.solver.parameter_tolerance;
  options.abort = abort;
  const SchurLmSummary summary =
      schurLevenbergMarquardt(problem, active, options, &state->poses, &state->points);
  *solver_name =
      reduced_matrix == ReducedMatrix::kDense ? kNativeDenseSchurName : kNativeSparseSchurName;
  *aborted = *aborted || summary.aborted;
  PassOutcome outcome;
  outcome.solved = summary.solved;
  outcome.initial_cost = summary.initial_cost;
  outcome.final_cost = summary.final_cost;
  outcome.iterations = summary.successful_steps + summary.unsuccessful_steps;
  return outcome;
}

// Our own solver's reduced matrix for a pass, or nullopt for Ceres: as the config asks, or for
// kAuto by the free keyframes (dense up to native_max_free_keyframes, sparse above if
// native_sparse).
std::optional<ReducedMatrix> nativeSolver(const BundleAdjustmentProblem& problem,
                                          const std::vector<std::uint8_t>& active,
                                          const BundleAdjustmentConfig& config) {
  switch (config.linear_solver) {
    case BaLinearSolver::kNativeDenseSchur:
      return ReducedMatrix::kDense;
    case BaLinearSolver::kNativeSparseSchur:
      return ReducedMatrix::kSparse;
    case BaLinearSolver::kAuto:
      break;
    default:
      return std::nullopt;
  }
  if (config.native_max_free_keyframes > 0 &&
      countFreeKeyframes(problem, active) <= config.native_max_free_keyframes) {
    return ReducedMatrix::kDense;
  }
  if (config.native_sparse) return ReducedMatrix::kSparse;
  return std::nullopt;
}

// One solve over the observations with active[i] != 0: by solveNativePass when nativeSolver
// says so, else by Ceres.
PassOutcome solvePass(const BundleAdjustmentProblem& problem,
                      const std::vector<std::uint8_t>& active, bool robust, int iterations,
                      double time_limit_s, const BundleAdjustmentConfig& config, BaModel* model,
                      BaState* state, const std::atomic<bool>* abort, bool* aborted,
                      std::string* solver_name) {
  if (const std::optional<ReducedMatrix> native = nativeSolver(problem, active, config)) {
    return solveNativePass(problem, active, *native, robust, iterations, time_limit_s, config,
                           *model, state, abort, aborted, solver_name);
  }
  ceres::Problem::Options problem_options;
  problem_options.loss_function_ownership = ceres::DO_NOT_TAKE_OWNERSHIP;
  problem_options.manifold_ownership = ceres::DO_NOT_TAKE_OWNERSHIP;
  ceres::Problem ceres_problem(problem_options);
  std::vector<std::uint8_t> pose_used(problem.keyframes.size(), 0);
  std::vector<std::uint8_t> point_used(problem.landmarks.size(), 0);
  for (size_t i = 0; i < problem.observations.size(); ++i) {
    if (!active[i]) continue;
    const BaObservation& o = problem.observations[i];
    ceres::LossFunction* loss = nullptr;
    if (robust) loss = o.dimension() == 3 ? &model->huber_stereo : &model->huber_mono;
    ceres_problem.AddResidualBlock(newReprojectionCost(problem.camera, o), loss,
                                   state->poses[o.keyframe].data(),
                                   state->points[o.landmark].data());
    pose_used[o.keyframe] = 1;
    point_used[o.landmark] = 1;
  }
  PassOutcome outcome;
  if (ceres_problem.NumResidualBlocks() == 0) return outcome;
  AbortCallback abort_callback(abort, aborted);

  // Landmarks first (eliminated by the Schur solvers), then the poses.
  auto ordering = std::make_shared<ceres::ParameterBlockOrdering>();
  for (size_t l = 0; l < problem.landmarks.size(); ++l) {
    if (point_used[l]) ordering->AddElementToGroup(state->points[l].data(), 0);
  }
  int num_free_keyframes = 0;
  for (size_t k = 0; k < problem.keyframes.size(); ++k) {
    if (!pose_used[k]) continue;
    double* x = state->poses[k].data();
    ordering->AddElementToGroup(x, 1);
    if (problem.keyframes[k].fixed) {
      ceres_problem.SetParameterBlockConstant(x);
    } else {
      ceres_problem.SetManifold(x, &model->manifold);
      ++num_free_keyframes;
    }
  }

  ceres::Solver::Options options = solverOptions(config.solver, iterations, time_limit_s);
  options.linear_solver_type = linearSolverType(config, num_free_keyframes);
  options.sparse_linear_algebra_library_type = bestSparseLibrary();
  options.preconditioner_type = ceres::SCHUR_JACOBI;
  options.linear_solver_ordering = ordering;
  if (abort != nullptr) options.callbacks.push_back(&abort_callback);
  *solver_name = ceres::LinearSolverTypeToString(options.linear_solver_type);
  ceres::Solver::Summary summary;
  ceres::Solve(options, &ceres_problem, &summary);
  outcome.solved = true;
  outcome.usable = summary.IsSolutionUsable();
  outcome.initial_cost = summary.initial_cost;
  outcome.final_cost = summary.final_cost;
  outcome.iterations = summary.num_successful_steps + summary.num_unsuccessful_steps;
  outcome.message = summary.message;
  return outcome;
}

std::string indexError(const char* what, size_t i, const std::string& message) {
  std::ostringstream os;
  os << what << ' ' << i << ": " << message;
  return os.str();
}

bool poseFinite(const Transformationd& T) {
  return T.rotation().coeffs().allFinite() && T.translation().allFinite();
}

}  // namespace

std::string validate(const BundleAdjustmentProblem& p) {
  if (const std::string e = validate(p.camera); !e.empty()) return "camera: " + e;
  if (p.keyframes.empty()) return "no keyframes";
  if (p.landmarks.empty()) return "no landmarks";
  if (p.observations.empty()) return "no observations";
  for (size_t k = 0; k < p.keyframes.size(); ++k) {
    if (!poseFinite(p.keyframes[k].T_C_G)) return indexError("keyframe", k, "T_C_G not finite");
  }
  for (size_t l = 0; l < p.landmarks.size(); ++l) {
    if (!p.landmarks[l].p_G.allFinite()) return indexError("landmark", l, "p_G not finite");
  }
  const auto num_keyframes = static_cast<int>(p.keyframes.size());
  const auto num_landmarks = static_cast<int>(p.landmarks.size());
  for (size_t i = 0; i < p.observations.size(); ++i) {
    const BaObservation& o = p.observations[i];
    if (o.keyframe < 0 || o.keyframe >= num_keyframes) {
      return indexError("observation", i,
                        "keyframe index " + std::to_string(o.keyframe) + " out of range [0, " +
                            std::to_string(num_keyframes) + ")");
    }
    if (o.landmark < 0 || o.landmark >= num_landmarks) {
      return indexError("observation", i,
                        "landmark index " + std::to_string(o.landmark) + " out of range [0, " +
                            std::to_string(num_landmarks) + ")");
    }
    if (const std::string e = validate(static_cast<const StereoMeasurement&>(o)); !e.empty()) {
      return indexError("observation", i, e);
    }
  }
  return {};
}

BundleAdjustmentConfig globalBundleAdjustmentConfig() {
  BundleAdjustmentConfig config;
  config.first_pass_iterations = 10;
  config.second_pass_iterations = 0;
  return config;
}

std::string validate(const BundleAdjustmentConfig& c) {
  if (c.first_pass_iterations < 1) return "first_pass_iterations must be >= 1";
  if (c.second_pass_iterations < 0) return "second_pass_iterations must be >= 0";
  if (!(c.chi2_mono > 0) || !(c.chi2_stereo > 0)) return "chi2 thresholds must be > 0";
  if (!(c.huber_delta_mono > 0) || !(c.huber_delta_stereo > 0)) {
    return "huber deltas must be > 0";
  }
  if (c.dense_schur_max_free_keyframes < 0) return "dense_schur_max_free_keyframes must be >= 0";
  if (c.native_max_free_keyframes < 0) return "native_max_free_keyframes must be >= 0";
  if (const std::string e = validate(c.solver); !e.empty()) return "solver: " + e;
  return {};
}

BundleAdjustmentResult bundleAdjust(const BundleAdjustmentProblem& problem,
                                    const BundleAdjustmentConfig& config,
                                    const std::atomic<bool>* abort) {
  const Clock::time_point start = Clock::now();
  if (const std::string e = validate(problem); !e.empty()) {
    throw std::invalid_argument("bundleAdjust: " + e);
  }
  if (const std::string e = validate(config); !e.empty()) {
    throw std::invalid_argument("bundleAdjust: config: " + e);
  }

  BaState state;
  state.poses.reserve(problem.keyframes.size());
  for (const BaKeyframe& kf : problem.keyframes) state.poses.push_back(toPoseParameters(kf.T_C_G));
  state.points.reserve(problem.landmarks.size());
  for (const BaLandmark& lm : problem.landmarks) state.points.push_back(lm.p_G);

  BundleAdjustmentResult result;
  BaModel model(config);
  const auto remaining_s = [&] {
    return config.solver.max_time_s - std::chrono::duration<double>(Clock::now() - start).count();
  };

  // Pass 1: every observation whose point is in front of its initial camera, robust loss.
  const size_t n = problem.observations.size();
  std::vector<std::uint8_t> active(n);
  for (size_t i = 0; i < n; ++i) {
    active[i] = std::isfinite(observationChi2(problem, state, problem.observations[i]));
  }
  PassOutcome pass =
      solvePass(problem, active, true, config.first_pass_iterations, config.solver.max_time_s,
                config, &model, &state, abort, &result.aborted, &result.linear_solver);
  bool usable = !pass.solved || pass.usable;
  if (pass.solved) {
    result.initial_cost = pass.initial_cost;
    result.final_cost = pass.final_cost;
    result.iterations += pass.iterations;
  }

  // Pass 2: without the outliers of pass 1.
  const double time_left_s = config.solver.max_time_s == 0.0 ? 0.0 : remaining_s();
  const bool has_time = config.solver.max_time_s == 0.0 || time_left_s > 0.0;
  if (usable && config.second_pass_iterations > 0 && !result.aborted && has_time) {
    for (size_t i = 0; i < n; ++i) {
      const BaObservation& o = problem.observations[i];
      active[i] = isInlier(config, o, observationChi2(problem, state, o));
    }
    pass = solvePass(problem, active, config.robust_loss_in_second_pass,
                     config.second_pass_iterations, time_left_s, config, &model, &state, abort,
                     &result.aborted, &result.linear_solver);
    if (pass.solved) {
      usable = pass.usable;
      result.final_cost = pass.final_cost;
      result.iterations += pass.iterations;
    }
  }
  if (!usable) {
    result.success = false;
    result.message = "Ceres: " + pass.message;
  }

  // Final classification of every observation at the solution.
  result.outlier.resize(n);
  for (size_t i = 0; i < n; ++i) {
    const BaObservation& o = problem.observations[i];
    const double chi2 = observationChi2(problem, state, o);
    result.outlier[i] = !isInlier(config, o, chi2);
    if (result.outlier[i]) {
      ++result.num_outliers;
    } else {
      result.final_chi2 += chi2;
    }
  }
  result.T_C_G.reserve(state.poses.size());
  for (size_t k = 0; k < problem.keyframes.size(); ++k) {
    result.T_C_G.push_back(problem.keyframes[k].fixed ? problem.keyframes[k].T_C_G
                                                      : fromPoseParameters(state.poses[k].data()));
  }
  result.p_G = std::move(state.points);
  result.time_ms = std::chrono::duration<double, std::milli>(Clock::now() - start).count();
  return result;
}

}  // namespace cblox
