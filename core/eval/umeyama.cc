#include "core/eval/umeyama.h"

#include <cmath>

#include <Eigen/Geometry>
#include <Eigen/SVD>

namespace cblox {
namespace {

void setError(std::string* error, std::string message) {
  if (error != nullptr) *error = std::move(message);
}

// Below this ratio of the second to the largest singular value of the cross-covariance the
// rotation about the principal axis is undetermined.
constexpr double kDegenerateRatio = 1e-10;

}  // namespace

const char* alignmentTypeName(AlignmentType type) {
  switch (type) {
    case AlignmentType::kNone:
      return "none";
    case AlignmentType::kSE3:
      return "se3";
    case AlignmentType::kSim3:
      return "sim3";
  }
  return "unknown";
}

std::optional<AlignmentType> parseAlignmentType(const std::string& name) {
  if (name == "none") return AlignmentType::kNone;
  if (name == "se3") return AlignmentType::kSE3;
  if (name == "sim3") return AlignmentType::kSim3;
  return std::nullopt;
}

std::optional<Alignment> umeyamaAlign(const std::vector<Eigen::Vector3d>& points_B,
                                      const std::vector<Eigen::Vector3d>& points_A,
                                      AlignmentType type, std::string* error) {
  if (points_B.size() != points_A.size()) {
    setError(error, "umeyamaAlign: point sets differ in size (" + std::to_string(points_B.size()) +
                        " source vs " + std::to_string(points_A.size()) + " target points)");
    return std::nullopt;
  }
  for (size_t i = 0; i < points_B.size(); ++i) {
    if (!points_B[i].allFinite() || !points_A[i].allFinite()) {
      setError(error, "umeyamaAlign: point " + std::to_string(i) + " is not finite");
      return std::nullopt;
    }
  }
  if (type == AlignmentType::kNone) return Alignment{};
  const size_t n = points_B.size();
  if (n < 3) {
    setError(error, std::string("umeyamaAlign: ") + alignmentTypeName(type) +
                        " alignment needs at least 3 point pairs, got " + std::to_string(n));
    return std::nullopt;
  }

  Eigen::Matrix3Xd source(3, static_cast<Eigen::Index>(n));
  Eigen::Matrix3Xd target(3, static_cast<Eigen::Index>(n));
  for (size_t i = 0; i < n; ++i) {
    source.col(static_cast<Eigen::Index>(i)) = points_B[i];
    target.col(static_cast<Eigen::Index>(i)) = points_A[i];
  }
  // Degeneracy test on the singular values of the cross-covariance (Umeyama's Eq. (38)); the
  // 1/n factor does not change their ratio.
  const Eigen::Matrix3d sigma_AB = (target.colwise() - target.rowwise().mean()) *
                                   (source.colwise() - source.rowwise().mean()).transpose();
  const Eigen::Vector3d d = Eigen::JacobiSVD<Eigen::Matrix3d>(sigma_AB).singularValues();
  if (!(d(0) > 0.0) || d(1) <= kDegenerateRatio * d(0)) {
    setError(error, std::string("umeyamaAlign: degenerate configuration for ") +
                        alignmentTypeName(type) +
                        " alignment: points coincide or are collinear (cross-covariance "
                        "singular values " +
                        std::to_string(d(0)) + ", " + std::to_string(d(1)) + ", " +
                        std::to_string(d(2)) + ")");
    return std::nullopt;
  }
  // Eigen's implementation of the paper, with the reflection fix; returns [s R, t; 0 1].
  const Eigen::Matrix4d T = Eigen::umeyama(source, target, type == AlignmentType::kSim3);
  const Eigen::Matrix3d sR = T.topLeftCorner<3, 3>();
  Alignment alignment;
  alignment.scale = type == AlignmentType::kSim3 ? std::cbrt(sR.determinant()) : 1.0;
  alignment.T_A_B = Transformationd(Eigen::Matrix3d(sR / alignment.scale),
                                    Eigen::Vector3d(T.topRightCorner<3, 1>()));
  return alignment;
}

}  // namespace cblox
