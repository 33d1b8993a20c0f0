#pragma once

// Central-difference Jacobians for the optimization tests.

#include <Eigen/Core>

namespace cblox::test {

/// d f / d x at x by central differences with step h: f maps a VectorXd of x.size() to a
/// VectorXd of fixed size.
template <typename F>
Eigen::MatrixXd numericJacobian(const F& f, const Eigen::VectorXd& x, double h) {
  const Eigen::VectorXd f0 = f(x);
  Eigen::MatrixXd J(f0.size(), x.size());
  for (int c = 0; c < x.size(); ++c) {
    Eigen::VectorXd xp = x, xm = x;
    xp[c] += h;
    xm[c] -= h;
    J.col(c) = (f(xp) - f(xm)) / (2.0 * h);
  }
  return J;
}

}  // namespace cblox::test
