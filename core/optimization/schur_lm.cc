#include "core/optimization/schur_lm.h"

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>

#include <Eigen/Cholesky>
#include <Eigen/LU>

#include "core/optimization/bundle_adjustment.h"
#include "core/optimization/reduced_camera_system.h"
#include "core/optimization/reprojection_error.h"

namespace cblox {
namespace {

using Clock = std::chrono::steady_clock;
using Mat33 = Eigen::Matrix3d;
using Mat63 = Eigen::Matrix<double, 6, 3>;
using Mat66 = Eigen::Matrix<double, 6, 6>;
using Vec3 = Eigen::Vector3d;
using Vec6 = Eigen::Matrix<double, 6, 1>;
using RowMajor33 = Eigen::Matrix<double, 3, 3, Eigen::RowMajor>;

// Ceres' Levenberg-Marquardt defaults (ceres::Solver::Options).
constexpr double kMinDiagonal = 1e-6;
constexpr double kMaxDiagonal = 1e32;
constexpr double kInitialRadius = 1e4;
constexpr double kMaxRadius = 1e16;
constexpr double kMinRadius = 1e-32;
constexpr double kMinRelativeDecrease = 1e-3;

// rho(chi2) and its weight rho'(chi2) by the options' loss functions (identity if none).
struct Loss {
  const ceres::LossFunction* mono = nullptr;
  const ceres::LossFunction* stereo = nullptr;
  double rho(double chi2, int dimension) const { return evaluate(chi2, dimension)[0]; }
  double weight(double chi2, int dimension) const { return evaluate(chi2, dimension)[1]; }

 private:
  std::array<double, 3> evaluate(double chi2, int dimension) const {
    std::array<double, 3> rho = {chi2, 1.0, 0.0};
    const ceres::LossFunction* f = dimension == 3 ? stereo : mono;
    if (f != nullptr) f->Evaluate(chi2, rho.data());
    return rho;
  }
};

// The active observations grouped by landmark (CSR), each with the index of its keyframe
// among the free keyframes (-1 for a fixed keyframe).
struct Structure {
  std::vector<int> landmarks;      // problem landmark per group
  std::vector<int> offsets;        // group g: entries [offsets[g], offsets[g + 1])
  std::vector<int> observations;   // problem observation per entry
  std::vector<int> free_index;     // free keyframe per entry, or -1
  std::vector<int> free_keyframes; // problem keyframe per free keyframe
};

Structure buildStructure(const BundleAdjustmentProblem& problem,
                         const std::vector<std::uint8_t>& active) {
  Structure s;
  std::vector<int> count(problem.landmarks.size(), 0);
  std::vector<int> free_of(problem.keyframes.size(), -1);
  for (size_t i = 0; i < problem.observations.size(); ++i) {
    if (!active[i]) continue;
    const BaObservation& o = problem.observations[i];
    ++count[static_cast<size_t>(o.landmark)];
    const auto k = static_cast<size_t>(o.keyframe);
    if (!problem.keyframes[k].fixed && free_of[k] < 0) {
      free_of[k] = static_cast<int>(s.free_keyframes.size());
      s.free_keyframes.push_back(o.keyframe);
    }
  }
  std::vector<int> group_of(problem.landmarks.size(), -1);
  s.offsets.push_back(0);
  for (size_t l = 0; l < count.size(); ++l) {
    if (count[l] == 0) continue;
    group_of[l] = static_cast<int>(s.landmarks.size());
    s.landmarks.push_back(static_cast<int>(l));
    s.offsets.push_back(s.offsets.back() + count[l]);
  }
  s.observations.resize(static_cast<size_t>(s.offsets.back()));
  s.free_index.resize(s.observations.size());
  std::vector<int> next(s.offsets.begin(), s.offsets.end() - 1);
  for (size_t i = 0; i < problem.observations.size(); ++i) {
    if (!active[i]) continue;
    const BaObservation& o = problem.observations[i];
    const auto e = static_cast<size_t>(next[static_cast<size_t>(group_of[o.landmark])]++);
    s.observations[e] = static_cast<int>(i);
    s.free_index[e] = free_of[static_cast<size_t>(o.keyframe)];
  }
  return s;
}

// The unknowns in the form the steps use.
struct State {
  std::vector<Transformationd> T_C_G;  // per problem keyframe
  std::vector<Mat33> R_C_G;
  std::vector<Vec3> p_G;  // per problem landmark
  void updateRotations() {
    R_C_G.resize(T_C_G.size());
    for (size_t k = 0; k < T_C_G.size(); ++k) R_C_G[k] = T_C_G[k].rotationMatrix();
  }
};

// Cost 1/2 sum rho(chi2) at a state, or +inf if a point is behind its camera.
double cost(const BundleAdjustmentProblem& problem, const Structure& s, const Loss& loss,
            const State& x) {
  double sum = 0.0;
  for (const int i : s.observations) {
    const BaObservation& o = problem.observations[static_cast<size_t>(i)];
    const auto k = static_cast<size_t>(o.keyframe);
    const Vec3 p_C = x.R_C_G[k] * x.p_G[static_cast<size_t>(o.landmark)] + x.T_C_G[k].translation();
    const double chi2 = reprojectionChi2(problem.camera, o, p_C);
    if (!std::isfinite(chi2)) return HUGE_VAL;
    sum += loss.rho(chi2, o.dimension());
  }
  return 0.5 * sum;
}

// The weighted normal equations H dx = b (b = -gradient) at a state, in blocks: per free
// keyframe, per landmark group, and the keyframe-landmark block W per entry (zero for
// fixed keyframes).
struct Linearization {
  std::vector<Mat66> H_pp;
  std::vector<Vec6> b_p;
  std::vector<Mat33> H_ll;
  std::vector<Vec3> b_l;
  std::vector<Mat63> W;
  double max_gradient = 0.0;
};

void linearize(const BundleAdjustmentProblem& problem, const Structure& s, const Loss& loss,
               const State& x, Linearization* lin) {
  const size_t groups = s.landmarks.size();
  lin->H_pp.assign(s.free_keyframes.size(), Mat66::Zero());
  lin->b_p.assign(s.free_keyframes.size(), Vec6::Zero());
  lin->H_ll.resize(groups);
  lin->b_l.resize(groups);
  lin->W.resize(s.observations.size());
  for (size_t g = 0; g < groups; ++g) {
    Mat33 H_ll = Mat33::Zero();
    Vec3 b_l = Vec3::Zero();
    const Vec3& p_G = x.p_G[static_cast<size_t>(s.landmarks[g])];
    for (auto e = static_cast<size_t>(s.offsets[g]); e < static_cast<size_t>(s.offsets[g + 1]);
         ++e) {
      const BaObservation& o = problem.observations[static_cast<size_t>(s.observations[e])];
      const auto k = static_cast<size_t>(o.keyframe);
      const Vec3 p_C = x.R_C_G[k] * p_G + x.T_C_G[k].translation();
      Vec3 r = Vec3::Zero();
      RowMajor33 A = RowMajor33::Zero();  // mono: the third row stays zero
      if (!weightedReprojectionResidual(problem.camera, o, p_C, r.data(), A.data())) {
        lin->W[e].setZero();  // cannot happen at an accepted state
        continue;
      }
      const double w = loss.weight(r.squaredNorm(), o.dimension());
      const Mat33 J_l = A * x.R_C_G[k];
      H_ll.noalias() += w * J_l.transpose() * J_l;
      b_l.noalias() -= w * J_l.transpose() * r;
      const int f = s.free_index[e];
      if (f < 0) continue;
      Eigen::Matrix<double, 3, 6> J_p;
      J_p.leftCols<3>() = A;
      J_p.rightCols<3>() = -A * skew<double>(p_C);
      lin->H_pp[static_cast<size_t>(f)].noalias() += w * J_p.transpose() * J_p;
      lin->b_p[static_cast<size_t>(f)].noalias() -= w * J_p.transpose() * r;
      lin->W[e].noalias() = w * J_p.transpose() * J_l;
    }
    lin->H_ll[g] = H_ll;
    lin->b_l[g] = b_l;
  }
  double m = 0.0;
  for (const Vec6& b : lin->b_p) m = std::max(m, b.cwiseAbs().maxCoeff());
  for (const Vec3& b : lin->b_l) m = std::max(m, b.cwiseAbs().maxCoeff());
  lin->max_gradient = m;
}

// The damped step: (H + D / radius) dx = b with D = diag(H) clamped, the landmarks
// eliminated. Returns false if the reduced camera matrix is not positive definite.
struct Step {
  Eigen::VectorXd dp;         // 6 per free keyframe
  std::vector<Vec3> dl;       // per group
  double model_decrease = 0;  // 1/2 dx^T (b + D / radius dx)
  double norm = 0;
};

template <int N>
Eigen::Matrix<double, N, 1> damping(const Eigen::Matrix<double, N, N>& H, double radius) {
  return H.diagonal().cwiseMax(kMinDiagonal).cwiseMin(kMaxDiagonal) / radius;
}

// The block pattern of the reduced camera matrix: for each free keyframe c, the free keyframes
// r <= c that share a landmark with it, ascending (c itself last).
std::vector<std::vector<int>> reducedPattern(const Structure& s) {
  std::vector<std::vector<int>> rows(s.free_keyframes.size());
  for (size_t g = 0; g + 1 < s.offsets.size(); ++g) {
    for (auto a = static_cast<size_t>(s.offsets[g]); a < static_cast<size_t>(s.offsets[g + 1]);
         ++a) {
      const int fa = s.free_index[a];
      if (fa < 0) continue;
      for (auto c = static_cast<size_t>(s.offsets[g]); c < static_cast<size_t>(s.offsets[g + 1]);
           ++c) {
        const int fc = s.free_index[c];
        if (fc >= fa) rows[static_cast<size_t>(fc)].push_back(fa);
      }
    }
  }
  for (std::vector<int>& r : rows) {
    std::sort(r.begin(), r.end());
    r.erase(std::unique(r.begin(), r.end()), r.end());
  }
  return rows;
}

template <class System>
bool solveStep(const Structure& s, const Linearization& lin, double radius, System* S,
               Step* step) {
  const size_t n = s.free_keyframes.size();
  const size_t groups = s.landmarks.size();
  S->setZero();
  Eigen::VectorXd rhs(static_cast<Eigen::Index>(6 * n));
  Eigen::VectorXd D_p(static_cast<Eigen::Index>(6 * n));
  for (size_t f = 0; f < n; ++f) {
    const auto i = static_cast<Eigen::Index>(6 * f);
    const Vec6 d = damping<6>(lin.H_pp[f], radius);
    ReducedBlockMap block = S->block(static_cast<int>(f), static_cast<int>(f));
    block = lin.H_pp[f];
    block.diagonal() += d;
    D_p.segment<6>(i) = d;
    rhs.segment<6>(i) = lin.b_p[f];
  }
  std::vector<Mat33> H_inv(groups);
  std::vector<Vec3> D_l(groups);
  std::vector<Mat63> V;
  for (size_t g = 0; g < groups; ++g) {
    D_l[g] = damping<3>(lin.H_ll[g], radius);
    Mat33 H = lin.H_ll[g];
    H.diagonal() += D_l[g];
    Eigen::LLT<Mat33> llt(H);
    if (llt.info() != Eigen::Success) return false;
    H_inv[g] = llt.solve(Mat33::Identity());
    const auto begin = static_cast<size_t>(s.offsets[g]);
    const auto end = static_cast<size_t>(s.offsets[g + 1]);
    V.resize(end - begin);
    for (size_t a = begin; a < end; ++a) {
      const int fa = s.free_index[a];
      if (fa < 0) continue;
      V[a - begin].noalias() = lin.W[a] * H_inv[g];
      rhs.segment<6>(6 * fa).noalias() -= V[a - begin] * lin.b_l[g];
    }
    // S -= sum over pairs of W_a H^-1 W_c^T, into the upper block triangle (both orders of
    // a pair within one diagonal block).
    for (size_t a = begin; a < end; ++a) {
      const int fa = s.free_index[a];
      if (fa < 0) continue;
      for (size_t c = begin; c < end; ++c) {
        const int fc = s.free_index[c];
        if (fc < fa) continue;
        S->block(fa, fc).noalias() -= V[a - begin] * lin.W[c].transpose();
      }
    }
  }
  if (!S->solve(rhs, &step->dp)) return false;
  double decrease = 0.0;
  double norm2 = step->dp.squaredNorm();
  for (size_t f = 0; f < n; ++f) {
    const Vec6 d = step->dp.segment<6>(static_cast<Eigen::Index>(6 * f));
    decrease += d.dot(lin.b_p[f]) +
                d.dot(D_p.segment<6>(static_cast<Eigen::Index>(6 * f)).cwiseProduct(d));
  }
  step->dl.resize(groups);
  for (size_t g = 0; g < groups; ++g) {
    Vec3 b = lin.b_l[g];
    for (auto e = static_cast<size_t>(s.offsets[g]); e < static_cast<size_t>(s.offsets[g + 1]);
         ++e) {
      const int f = s.free_index[e];
      if (f >= 0) b.noalias() -= lin.W[e].transpose() * step->dp.segment<6>(6 * f);
    }
    step->dl[g].noalias() = H_inv[g] * b;
    const Vec3& d = step->dl[g];
    decrease += d.dot(lin.b_l[g]) + d.dot(D_l[g].cwiseProduct(d));
    norm2 += d.squaredNorm();
  }
  step->model_decrease = 0.5 * decrease;
  step->norm = std::sqrt(norm2);
  return std::isfinite(step->norm);
}

// The Levenberg-Marquardt iterations from state x (cost `current`) with the reduced camera
// system `S`; returns the final cost and counts the steps in *summary.
template <class System>
double iterate(const BundleAdjustmentProblem& problem, const Structure& s, const Loss& loss,
               const SchurLmOptions& options, Clock::time_point start, System* S, State* x_io,
               double current, SchurLmSummary* summary_io) {
  State& x = *x_io;
  SchurLmSummary& summary = *summary_io;
  Linearization lin;
  Step step;
  State candidate;
  double radius = kInitialRadius;
  double decrease_factor = 2.0;
  bool linearized = false;
  while (summary.successful_steps + summary.unsuccessful_steps < options.max_iterations) {
    if (options.abort != nullptr && options.abort->load(std::memory_order_relaxed)) {
      summary.aborted = true;
      break;
    }
    if (options.time_limit_s > 0.0 &&
        std::chrono::duration<double>(Clock::now() - start).count() >= options.time_limit_s) {
      break;
    }
    if (!linearized) {
      linearize(problem, s, loss, x, &lin);
      linearized = true;
      if (lin.max_gradient <= options.gradient_tolerance) break;
    }
    bool success = solveStep(s, lin, radius, S, &step);
    if (success) {
      double x_norm2 = 0.0;
      for (const int k : s.free_keyframes) {
        x_norm2 += 1.0 + x.T_C_G[static_cast<size_t>(k)].translation().squaredNorm();
      }
      for (const int l : s.landmarks) x_norm2 += x.p_G[static_cast<size_t>(l)].squaredNorm();
      if (step.norm <= options.parameter_tolerance *
                           (std::sqrt(x_norm2) + options.parameter_tolerance)) {
        break;
      }
      candidate = x;
      for (size_t f = 0; f < s.free_keyframes.size(); ++f) {
        Transformationd& T = candidate.T_C_G[static_cast<size_t>(s.free_keyframes[f])];
        T = Transformationd::exp(step.dp.segment<6>(static_cast<Eigen::Index>(6 * f))) * T;
      }
      for (size_t g = 0; g < s.landmarks.size(); ++g) {
        candidate.p_G[static_cast<size_t>(s.landmarks[g])] += step.dl[g];
      }
      candidate.updateRotations();
      const double next = cost(problem, s, loss, candidate);
      success = std::isfinite(next) && step.model_decrease > 0.0 &&
                (current - next) / step.model_decrease > kMinRelativeDecrease;
      if (success) {
        const double quality = (current - next) / step.model_decrease;
        radius = std::min(kMaxRadius,
                          radius / std::max(1.0 / 3.0, 1.0 - std::pow(2.0 * quality - 1.0, 3)));
        decrease_factor = 2.0;
        const bool converged = current - next <= options.function_tolerance * current;
        std::swap(x, candidate);
        current = next;
        linearized = false;
        ++summary.successful_steps;
        if (converged) break;
        continue;
      }
    }
    ++summary.unsuccessful_steps;
    radius /= decrease_factor;
    decrease_factor *= 2.0;
    if (radius < kMinRadius) break;
  }
  return current;
}

}  // namespace

SchurLmSummary schurLevenbergMarquardt(const BundleAdjustmentProblem& problem,
                                       const std::vector<std::uint8_t>& active,
                                       const SchurLmOptions& options,
                                       std::vector<PoseParameters>* poses,
                                       std::vector<Eigen::Vector3d>* points) {
  const Clock::time_point start = Clock::now();
  SchurLmSummary summary;
  const Structure s = buildStructure(problem, active);
  if (s.observations.empty()) return summary;
  summary.solved = true;
  const Loss loss{options.loss_mono, options.loss_stereo};

  State x;
  x.T_C_G.reserve(poses->size());
  for (const PoseParameters& p : *poses) x.T_C_G.push_back(fromPoseParameters(p.data()));
  x.p_G = *points;
  x.updateRotations();
  double current = cost(problem, s, loss, x);
  summary.initial_cost = current;

  const int n = static_cast<int>(s.free_keyframes.size());
  if (options.reduced_matrix == ReducedMatrix::kSparse && n > 0) {
    SparseReducedCameraSystem S(n, reducedPattern(s));
    current = iterate(problem, s, loss, options, start, &S, &x, current, &summary);
  } else {
    DenseReducedCameraSystem S(n, {});
    current = iterate(problem, s, loss, options, start, &S, &x, current, &summary);
  }
  summary.final_cost = current;
  for (const int k : s.free_keyframes) {
    (*poses)[static_cast<size_t>(k)] = toPoseParameters(x.T_C_G[static_cast<size_t>(k)]);
  }
  for (const int l : s.landmarks) (*points)[static_cast<size_t>(l)] = x.p_G[static_cast<size_t>(l)];
  return summary;
}

}  // namespace cblox
