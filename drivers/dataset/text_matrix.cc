#include "drivers/dataset/text_matrix.h"

#include <cerrno>
#include <cmath>
#include <cstdlib>
#include <fstream>
#include <vector>

namespace cblox {
namespace {

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

}  // namespace cblox
