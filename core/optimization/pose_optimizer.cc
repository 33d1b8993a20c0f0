#include "core/optimization/pose_optimizer.h"

#include <algorithm>
#include <limits>
#include <sstream>
#include <stdexcept>

#include <Eigen/Cholesky>

namespace cblox {
namespace {

using Vec6 = Eigen::Matrix<double, 6, 1>;
using Mat6 = Eigen::Matrix<double, 6, 6>;

constexpr int kMaxTriesPerIteration = 10;
constexpr double kInitialLambda = 1e-5;  // Marquardt damping, relative to diag(H)
constexpr double kMinLambda = 1e-12;

// Gauss-Newton system of the (robustified) cost sum_i rho(chi2_i) at a pose.
struct Linearization {
  Mat6 H = Mat6::Zero();
  Vec6 b = Vec6::Zero();  // gradient / 2
  double cost = 0.0;
};

class PoseCost {
 public:
  PoseCost(const StereoCameraModel& camera, std::span<const PoseObservation> observations,
           const PoseOptimizerConfig& config)
      : camera_(camera), observations_(observations), config_(config) {}

  // Linearises over the active observations; cost = +inf if one of them is behind the camera.
  // With `robust`, IRLS weights of the Huber kernel: w = 1 inside, delta / sqrt(chi2) outside.
  Linearization linearize(const Transformationd& T, std::span<const std::uint8_t> active,
                          bool robust) const {
    Linearization lin;
    const Eigen::Matrix3d R = T.rotationMatrix();
    const Eigen::Vector3d& t = T.translation();
    for (size_t i = 0; i < observations_.size(); ++i) {
      if (!active[i]) continue;
      const PoseObservation& o = observations_[i];
      const Eigen::Vector3d p_C = R * o.p_G + t;
      Eigen::Matrix<double, 3, 3, Eigen::RowMajor> A;
      Eigen::Vector3d r;
      if (!weightedReprojectionResidual(camera_, o, p_C, r.data(), A.data())) {
        lin.cost = std::numeric_limits<double>::infinity();
        return lin;
      }
      if (o.u_right >= 0.0) {
        accumulate<3>(A, r, p_C, robust ? config_.huber_delta_stereo : 0.0, &lin);
      } else {
        accumulate<2>(A, r, p_C, robust ? config_.huber_delta_mono : 0.0, &lin);
      }
    }
    lin.H.bottomLeftCorner<3, 3>() = lin.H.topRightCorner<3, 3>().transpose();
    return lin;
  }

  double chi2(const Transformationd& T, size_t i) const {
    return reprojectionChi2(camera_, observations_[i], T * observations_[i].p_G);
  }

  double threshold(size_t i) const {
    return observations_[i].u_right >= 0.0 ? config_.chi2_stereo : config_.chi2_mono;
  }

 private:
  template <int N>
  static void accumulate(const Eigen::Matrix<double, 3, 3, Eigen::RowMajor>& A_full,
                         const Eigen::Vector3d& r_full, const Eigen::Vector3d& p_C,
                         double huber_delta, Linearization* lin) {
    const auto A = A_full.topRows<N>();
    const auto r = r_full.head<N>();
    const double e = r.squaredNorm();
    double w = 1.0;
    if (huber_delta > 0.0 && e > huber_delta * huber_delta) {
      const double sqrt_e = std::sqrt(e);
      w = huber_delta / sqrt_e;
      lin->cost += 2.0 * huber_delta * sqrt_e - huber_delta * huber_delta;
    } else {
      lin->cost += e;
    }
    // Tangent Jacobian of the left perturbation: J = A * [I, -[p]x] (p = p_C). With
    // M = w A^T A and g = w A^T r: J^T J = [M, -M [p]x; [p]x M, -[p]x M [p]x] and
    // J^T r = [g; p x g]. Cheaper than forming J; the lower-left block is filled at the end.
    const Eigen::Matrix3d M = w * (A.transpose() * A);
    const Eigen::Vector3d g = w * (A.transpose() * r);
    const Eigen::Matrix3d P = skew<double>(p_C);
    const Eigen::Matrix3d MP = M * P;
    lin->H.template topLeftCorner<3, 3>() += M;
    lin->H.template topRightCorner<3, 3>() -= MP;
    lin->H.template bottomRightCorner<3, 3>() -= (P * MP).eval();
    lin->b.template head<3>() += g;
    lin->b.template tail<3>() += p_C.cross(g);
  }

  const StereoCameraModel& camera_;
  std::span<const PoseObservation> observations_;
  const PoseOptimizerConfig& config_;
};

// Levenberg-Marquardt on the active observations; returns the number of iterations. A
// step shorter than min_step_norm means convergence: it is applied without evaluating the
// cost (it cannot be told from rounding) and the round ends.
int runLevenbergMarquardt(const PoseCost& cost, std::span<const std::uint8_t> active, bool robust,
                          const PoseOptimizerConfig& config, Transformationd* T) {
  Linearization lin = cost.linearize(*T, active, robust);
  double lambda = kInitialLambda;
  int iterations = 0;
  for (int it = 0; it < config.iterations_per_round; ++it) {
    ++iterations;
    bool accepted = false;
    for (int attempt = 0; attempt < kMaxTriesPerIteration && !accepted; ++attempt) {
      Mat6 H = lin.H;
      for (int k = 0; k < 6; ++k) H(k, k) += lambda * std::max(lin.H(k, k), 1e-9);
      const Vec6 delta = H.ldlt().solve(-lin.b);
      if (!delta.allFinite()) return iterations;
      const Transformationd T_new = Transformationd::exp(delta) * *T;
      if (delta.norm() < config.min_step_norm) {
        *T = T_new;
        return iterations;
      }
      Linearization trial = cost.linearize(T_new, active, robust);
      if (trial.cost < lin.cost) {
        *T = T_new;
        lin = trial;
        lambda = std::max(lambda * 0.1, kMinLambda);
        accepted = true;
      } else {
        lambda *= 10.0;
      }
    }
    if (!accepted) break;
  }
  return iterations;
}

std::string observationError(size_t i, const std::string& what) {
  std::ostringstream os;
  os << "optimizePose: observation " << i << ": " << what;
  return os.str();
}

}  // namespace

std::string validate(const PoseOptimizerConfig& c) {
  if (c.rounds < 1) return "rounds must be >= 1";
  if (c.iterations_per_round < 1) return "iterations_per_round must be >= 1";
  if (c.robust_rounds < 0 || c.robust_rounds > c.rounds) {
    return "robust_rounds must be in [0, rounds]";
  }
  if (!(c.chi2_mono > 0) || !(c.chi2_stereo > 0)) return "chi2 thresholds must be > 0";
  if (!(c.huber_delta_mono > 0) || !(c.huber_delta_stereo > 0)) {
    return "huber deltas must be > 0";
  }
  if (!(c.min_step_norm >= 0)) return "min_step_norm must be >= 0";
  return {};
}

PoseOptimizationResult optimizePose(const StereoCameraModel& camera,
                                    const Transformationd& T_C_G_initial,
                                    std::span<const PoseObservation> observations,
                                    const PoseOptimizerConfig& config) {
  if (const std::string e = validate(camera); !e.empty()) {
    throw std::invalid_argument("optimizePose: camera: " + e);
  }
  if (const std::string e = validate(config); !e.empty()) {
    throw std::invalid_argument("optimizePose: config: " + e);
  }
  if (observations.empty()) throw std::invalid_argument("optimizePose: no observations");
  if (!T_C_G_initial.rotation().coeffs().allFinite() || !T_C_G_initial.translation().allFinite()) {
    throw std::invalid_argument("optimizePose: the initial pose is not finite");
  }
  for (size_t i = 0; i < observations.size(); ++i) {
    if (!observations[i].p_G.allFinite()) {
      throw std::invalid_argument(observationError(i, "p_G must be finite"));
    }
    if (const std::string e = validate(static_cast<const StereoMeasurement&>(observations[i]));
        !e.empty()) {
      throw std::invalid_argument(observationError(i, e));
    }
  }

  const PoseCost cost(camera, observations, config);
  PoseOptimizationResult result;
  result.T_C_G = T_C_G_initial;
  // The first round optimises over all observations in front of the initial camera (points
  // behind it cannot be linearised); the next ones over the inliers of the previous round,
  // which are in front of the camera by construction (chi2 finite).
  result.inlier.resize(observations.size());
  for (size_t i = 0; i < observations.size(); ++i) {
    result.inlier[i] = std::isfinite(cost.chi2(result.T_C_G, i));
  }
  for (int round = 0; round < config.rounds; ++round) {
    result.iterations += runLevenbergMarquardt(cost, result.inlier, round < config.robust_rounds,
                                               config, &result.T_C_G);
    result.num_inliers = 0;
    result.final_chi2 = 0.0;
    for (size_t i = 0; i < observations.size(); ++i) {
      const double e = cost.chi2(result.T_C_G, i);
      result.inlier[i] = e <= cost.threshold(i);
      if (result.inlier[i]) {
        ++result.num_inliers;
        result.final_chi2 += e;
      }
    }
  }
  for (size_t i = 0; i < observations.size(); ++i) {
    const double e = cost.chi2(T_C_G_initial, i);
    if (result.inlier[i] && std::isfinite(e)) result.initial_chi2 += e;
  }
  return result;
}

}  // namespace cblox
