#pragma once

#include <memory>
#include <vector>

#include <Eigen/Core>

namespace cblox {

/// The reduced camera system S x = b of one Schur-complement step of bundle adjustment
/// (schur_lm.h): S is symmetric positive definite, 6n x 6n in 6 x 6 blocks for n free
/// keyframes, and its block (r, c) is non-zero only if keyframes r and c see a common
/// landmark. Callers fill the UPPER block triangle: every block (r, c) with r <= c of the
/// pattern, the diagonal blocks completely (their lower halves are ignored).
///
/// Two implementations with the same interface, for schurLevenbergMarquardt's template:
/// - DenseReducedCameraSystem: S dense, solved by Eigen's LLT. For local windows (tens of
///   keyframes), where the blocks are mostly non-zero anyway.
/// - SparseReducedCameraSystem: S block-sparse, stored directly in CHOLMOD's compressed
///   columns (upper triangle), ordered by AMD and factorised by CHOLMOD (supernodal or
///   simplicial, CHOLMOD's choice) with the symbolic analysis done once for the pattern.
///   For whole maps (hundreds to thousands of keyframes), where S is sparse.
/// Neither is thread-safe; distinct objects may be used on distinct threads.

/// A 6 x 6 block of S, viewed in place.
using ReducedBlockMap = Eigen::Map<Eigen::Matrix<double, 6, 6>, 0, Eigen::OuterStride<>>;

class DenseReducedCameraSystem {
 public:
  /// n free keyframes; the pattern is unused (every block may be filled).
  DenseReducedCameraSystem(int n, const std::vector<std::vector<int>>& rows_of_column);
  /// S = 0.
  void setZero();
  /// Block (r, c), r <= c, of S (a view into it).
  ReducedBlockMap block(int r, int c);
  /// x = S^-1 b by Cholesky. False if S is not numerically positive definite (x is then
  /// unspecified).
  bool solve(const Eigen::VectorXd& b, Eigen::VectorXd* x);

 private:
  Eigen::MatrixXd S_;
};

class SparseReducedCameraSystem {
 public:
  /// n free keyframes; rows_of_column[c]: the keyframes r <= c whose block (r, c) may be
  /// non-zero, ascending, ending with c itself (the diagonal block). Throws
  /// std::invalid_argument if the pattern is malformed.
  SparseReducedCameraSystem(int n, const std::vector<std::vector<int>>& rows_of_column);
  ~SparseReducedCameraSystem();
  SparseReducedCameraSystem(const SparseReducedCameraSystem&) = delete;
  SparseReducedCameraSystem& operator=(const SparseReducedCameraSystem&) = delete;
  /// S = 0 (the pattern stays).
  void setZero();
  /// Block (r, c) of the pattern, r <= c (a view into CHOLMOD's values). Precondition: (r, c)
  /// is in the pattern.
  ReducedBlockMap block(int r, int c);
  /// x = S^-1 b by CHOLMOD (the ordering and symbolic factorisation on the first call, the
  /// numeric factorisation on each). False if S is not positive definite.
  bool solve(const Eigen::VectorXd& b, Eigen::VectorXd* x);
  /// Non-zero blocks of the upper triangle (the pattern's size).
  int numBlocks() const { return static_cast<int>(row_index_.size()); }

 private:
  struct Cholmod;  // CHOLMOD's common, matrix view and factor
  std::vector<int> column_start_;  // per block column: first block (index into row_index_)
  std::vector<int> row_index_;     // per block: its block row
  std::vector<double> values_;     // CHOLMOD's x: per block column, 6 scalar columns
  std::vector<int> scalar_column_pointers_;
  std::vector<int> scalar_row_indices_;
  std::unique_ptr<Cholmod> cholmod_;
};

}  // namespace cblox
