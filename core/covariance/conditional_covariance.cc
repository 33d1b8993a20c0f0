#include "core/covariance/conditional_covariance.h"

#include <Eigen/Cholesky>
#include <Eigen/Eigenvalues>

#include "core/optimization/cholmod_support.h"

namespace cblox {

using Matrix6d = Eigen::Matrix<double, 6, 6>;

std::string pairIdError(const ReducedCameraMatrix& S, const KeyframePair& pair) {
  for (const std::uint64_t id : {pair.i, pair.j}) {
    if (S.blockOf(id) < 0) {
      return "keyframe " + std::to_string(id) +
             " is not in the BA linearization (fixed, culled or unknown)";
    }
  }
  if (pair.i == pair.j) {
    return "i and j are the same keyframe (" + std::to_string(pair.i) + ")";
  }
  return {};
}

std::string marginalIdError(const ReducedCameraMatrix& S, const KeyframePair& pair) {
  return S.blockOf(pair.i) < 0 ? pairIdError(S, KeyframePair{pair.i, pair.i}) : std::string();
}

ConditionalCovariance failedPair(const KeyframePair& pair, std::string error) {
  ConditionalCovariance r;
  r.i = pair.i;
  r.j = pair.j;
  r.error = std::move(error);
  return r;
}

double certaintyOf(const Matrix6d& sigma) {
  Eigen::SelfAdjointEigenSolver<Matrix6d> eig(sigma, Eigen::EigenvaluesOnly);
  return 1.0 / eig.eigenvalues()[5];
}

namespace {

ConditionalCovariance succeeded(const KeyframePair& pair, const Matrix6d& sigma) {
  ConditionalCovariance r;
  r.i = pair.i;
  r.j = pair.j;
  r.sigma = 0.5 * (sigma + sigma.transpose());
  r.q = certaintyOf(r.sigma);
  if (!r.sigma.allFinite() || !(r.q > 0.0) || !std::isfinite(r.q)) {
    return failedPair(pair, std::string(kNotPositiveDefiniteError) +
                                " (non-finite or non-positive conditional covariance)");
  }
  r.ok = true;
  return r;
}

}  // namespace

ConditionalCovariance conditionalGivenFixed(const KeyframePair& pair, const Matrix6d& ii) {
  return succeeded(pair, ii);
}

ConditionalCovariance conditionalFromFactorBlock(const KeyframePair& pair, const Matrix6d& a) {
  const Matrix6d a_inv = a.triangularView<Eigen::Lower>().solve(Matrix6d::Identity());
  return succeeded(pair, a_inv.transpose() * a_inv);
}

ConditionalCovariance conditionalFromCovarianceBlocks(const KeyframePair& pair, const Matrix6d& ii,
                                                      const Matrix6d& ij, const Matrix6d& jj) {
  const Eigen::LLT<Matrix6d> llt(jj);
  if (llt.info() != Eigen::Success) {
    return failedPair(pair, std::string(kNotPositiveDefiniteError) +
                                " (marginal covariance of keyframe " + std::to_string(pair.j) +
                                " is not positive definite)");
  }
  return succeeded(pair, ii - ij * llt.solve(ij.transpose()));
}

std::vector<ConditionalCovariance> denseConditionalCovariances(
    const ReducedCameraMatrix& S, std::span<const KeyframePair> pairs) {
  const Eigen::MatrixXd dense(S.matrix);
  const Eigen::LLT<Eigen::MatrixXd> llt(dense);
  bool pd = llt.info() == Eigen::Success;
  Eigen::MatrixXd sigma;
  if (pd) {
    sigma = llt.solve(Eigen::MatrixXd::Identity(dense.rows(), dense.cols()));
    pd = sigma.allFinite();
  }
  std::vector<ConditionalCovariance> out;
  out.reserve(pairs.size());
  for (const KeyframePair& pair : pairs) {
    if (std::string e = pairIdError(S, pair); !e.empty()) {
      out.push_back(failedPair(pair, std::move(e)));
    } else if (!pd) {
      out.push_back(failedPair(pair, kNotPositiveDefiniteError));
    } else {
      const int a = 6 * S.blockOf(pair.i);
      const int b = 6 * S.blockOf(pair.j);
      out.push_back(conditionalFromCovarianceBlocks(
          pair, sigma.block<6, 6>(a, a), sigma.block<6, 6>(a, b), sigma.block<6, 6>(b, b)));
    }
  }
  return out;
}

}  // namespace cblox
