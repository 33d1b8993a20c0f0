#include "core/io/text_matrix.h"

#include <cerrno>
#include <cmath>
#include <cstdlib>
#include <fstream>
#include <sstream>
#include <vector>

#include <Eigen/LU>

namespace cblox {
namespace {

constexpr double kOrthonormalityTolerance = 1e-3;
constexpr double kLastRowTolerance = 1e-6;

std::optional<Eigen::MatrixXd> fail(std::string* error, const std::string& message) {
  if (error != nullptr) *error = message;
  return std::nullopt;
}

}  // namespace

std::optional<Eigen::MatrixXd> readTextMatrix(const std::string& path, int rows, int cols,
                                              std::string* error) {
  std::ifstream file(path);
  if (!file) return fail(error, path + ": cannot open file");
  const size_t expected = static_cast<size_t>(rows) * static_cast<size_t>(cols);
  std::vector<double> values;
  std::string token;
  while (file >> token) {
    errno = 0;
    char* end = nullptr;
    const double value = std::strtod(token.c_str(), &end);
    if (end == token.c_str() || *end != '\0') {
      return fail(error, path + ": '" + token + "' is not a number");
    }
    if (errno == ERANGE || !std::isfinite(value)) {
      return fail(error, path + ": value '" + token + "' is out of range or not finite");
    }
    values.push_back(value);
    if (values.size() > expected) break;  // enough to report a count mismatch
  }
  if (file.bad()) return fail(error, path + ": read error");
  if (values.size() != expected) {
    return fail(error, path + ": expected " + std::to_string(expected) + " numbers (" +
                           std::to_string(rows) + "x" + std::to_string(cols) + "), found " +
                           (values.size() > expected ? "more" : std::to_string(values.size())));
  }
  Eigen::MatrixXd m(rows, cols);
  for (int r = 0; r < rows; ++r) {
    for (int c = 0; c < cols; ++c) m(r, c) = values[static_cast<size_t>(r * cols + c)];
  }
  return m;
}

std::string validateRigidTransform(const Eigen::Matrix4d& M) {
  if ((M.row(3) - Eigen::RowVector4d(0, 0, 0, 1)).cwiseAbs().maxCoeff() > kLastRowTolerance) {
    std::ostringstream os;
    os << "last row must be 0 0 0 1, got " << M.row(3);
    return os.str();
  }
  const Eigen::Matrix3d R = M.topLeftCorner<3, 3>();
  const double deviation = (R.transpose() * R - Eigen::Matrix3d::Identity()).cwiseAbs().maxCoeff();
  if (deviation > kOrthonormalityTolerance) {
    std::ostringstream os;
    os << "rotation is not orthonormal (max |R^T R - I| = " << deviation << ", tolerance "
       << kOrthonormalityTolerance << ")";
    return os.str();
  }
  if (R.determinant() < 0) return "rotation is a reflection (det < 0)";
  return {};
}

}  // namespace cblox
