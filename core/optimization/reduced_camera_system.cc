#include "core/optimization/reduced_camera_system.h"

#include <algorithm>
#include <stdexcept>
#include <string>

#include <Eigen/Cholesky>

#include "core/optimization/cholmod_support.h"

namespace cblox {

DenseReducedCameraSystem::DenseReducedCameraSystem(
    int n, const std::vector<std::vector<int>>& /*rows_of_column*/)
    : S_(6 * n, 6 * n) {}

void DenseReducedCameraSystem::setZero() { S_.setZero(); }

ReducedBlockMap DenseReducedCameraSystem::block(int r, int c) {
  return ReducedBlockMap(S_.data() + static_cast<Eigen::Index>(6 * c) * S_.rows() + 6 * r, 6, 6,
                  Eigen::OuterStride<>(S_.rows()));
}

bool DenseReducedCameraSystem::solve(const Eigen::VectorXd& b, Eigen::VectorXd* x) {
  Eigen::LLT<Eigen::MatrixXd, Eigen::Upper> llt(S_);
  if (llt.info() != Eigen::Success) return false;
  *x = llt.solve(b);
  return x->allFinite();
}

struct SparseReducedCameraSystem::Cholmod {
  CholmodCommon common;
  cholmod_sparse view{};
  CholmodFactor factor;
};

SparseReducedCameraSystem::SparseReducedCameraSystem(
    int n, const std::vector<std::vector<int>>& rows_of_column)
    : cholmod_(std::make_unique<Cholmod>()) {
  if (n < 1 || rows_of_column.size() != static_cast<size_t>(n)) {
    throw std::invalid_argument("SparseReducedCameraSystem: the pattern must have n >= 1 columns");
  }
  column_start_.reserve(static_cast<size_t>(n) + 1);
  for (int c = 0; c < n; ++c) {
    const std::vector<int>& rows = rows_of_column[static_cast<size_t>(c)];
    if (rows.empty() || rows.back() != c || rows.front() < 0 ||
        !std::is_sorted(rows.begin(), rows.end()) ||
        std::adjacent_find(rows.begin(), rows.end()) != rows.end()) {
      throw std::invalid_argument("SparseReducedCameraSystem: column " + std::to_string(c) +
                                  " must list distinct ascending rows ending with itself");
    }
    column_start_.push_back(static_cast<int>(row_index_.size()));
    row_index_.insert(row_index_.end(), rows.begin(), rows.end());
  }
  column_start_.push_back(static_cast<int>(row_index_.size()));
  values_.assign(36 * row_index_.size(), 0.0);
  // Scalar compressed columns: column 6c + j holds rows 6r + i of every block (r, c), in
  // block order, so a block is a 6 x 6 column-major matrix with the column's stride.
  scalar_column_pointers_.reserve(6 * static_cast<size_t>(n) + 1);
  scalar_row_indices_.reserve(values_.size());
  scalar_column_pointers_.push_back(0);
  for (int c = 0; c < n; ++c) {
    for (int j = 0; j < 6; ++j) {
      for (int k = column_start_[c]; k < column_start_[c + 1]; ++k) {
        for (int i = 0; i < 6; ++i) scalar_row_indices_.push_back(6 * row_index_[k] + i);
      }
      scalar_column_pointers_.push_back(static_cast<int>(scalar_row_indices_.size()));
    }
  }
  // Upper triangle: the lower halves of the diagonal blocks are ignored.
  cholmod_->view = cholmodUpperView(6 * n, scalar_column_pointers_.data(),
                                    scalar_row_indices_.data(), values_.data());
}

SparseReducedCameraSystem::~SparseReducedCameraSystem() = default;

void SparseReducedCameraSystem::setZero() { std::fill(values_.begin(), values_.end(), 0.0); }

ReducedBlockMap SparseReducedCameraSystem::block(int r, int c) {
  const auto begin = row_index_.begin() + column_start_[c];
  const auto end = row_index_.begin() + column_start_[c + 1];
  const int k = static_cast<int>(std::lower_bound(begin, end, r) - row_index_.begin());
  const int blocks = column_start_[c + 1] - column_start_[c];
  return ReducedBlockMap(values_.data() + 36 * static_cast<size_t>(column_start_[c]) +
                      6 * static_cast<size_t>(k - column_start_[c]),
                  6, 6, Eigen::OuterStride<>(6 * blocks));
}

bool SparseReducedCameraSystem::solve(const Eigen::VectorXd& b, Eigen::VectorXd* x) {
  cholmod_common* common = cholmod_->common.get();
  if (!cholmod_->factor) {
    common->nmethods = 1;
    common->method[0].ordering = CHOLMOD_AMD;
    common->final_ll = 1;  // LL': a simplicial LDL' would accept negative pivots
    cholmod_->factor = CholmodFactor(cholmod_analyze(&cholmod_->view, common), &cholmod_->common);
    if (!cholmod_->factor) return false;
  }
  cholmod_factor* L = cholmod_->factor.get();
  if (!cholmod_factorize(&cholmod_->view, L, common) || common->status == CHOLMOD_NOT_POSDEF ||
      L->minor < L->n) {
    return false;
  }
  cholmod_dense B{};
  B.nrow = static_cast<size_t>(b.size());
  B.ncol = 1;
  B.nzmax = B.nrow;
  B.d = B.nrow;
  B.x = const_cast<double*>(b.data());  // read only: CHOLMOD's API is not const-correct
  B.xtype = CHOLMOD_REAL;
  B.dtype = CHOLMOD_DOUBLE;
  cholmod_dense* X = cholmod_solve(CHOLMOD_A, L, &B, common);
  if (X == nullptr) return false;
  *x = Eigen::Map<const Eigen::VectorXd>(static_cast<const double*>(X->x), b.size());
  cholmod_free_dense(&X, common);
  return x->allFinite();
}

}  // namespace cblox
