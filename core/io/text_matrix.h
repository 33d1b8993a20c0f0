#pragma once

#include <optional>
#include <string>

#include <Eigen/Core>

namespace cblox {

/// Reads a rows x cols matrix from a text file of whitespace-separated numbers in row-major
/// order (line breaks are not significant). Returns std::nullopt and, if error is non-null,
/// a message that starts with the path when the file cannot be opened, a token is not a
/// number, a value is not finite, or the file holds other than rows * cols numbers.
/// Thread-safe (no shared state).
std::optional<Eigen::MatrixXd> readTextMatrix(const std::string& path, int rows, int cols,
                                              std::string* error);

/// Checks that M is a rigid transform: last row 0 0 0 1 (within 1e-6) and an orthonormal
/// (max |R^T R - I| <= 1e-3), right-handed rotation. Returns an empty string if so, else what is
/// wrong, e.g. "rotation is a reflection (det < 0)", for the caller to prefix with the file.
/// Thread-safe (no shared state).
std::string validateRigidTransform(const Eigen::Matrix4d& M);

}  // namespace cblox
