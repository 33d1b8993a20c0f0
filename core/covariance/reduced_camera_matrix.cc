#include "core/covariance/reduced_camera_matrix.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include <Eigen/Eigenvalues>

namespace cblox {
namespace {

using Matrix6d = Eigen::Matrix<double, 6, 6>;
using Matrix63d = Eigen::Matrix<double, 6, 3>;
using RowIterator = Eigen::SparseMatrix<double, Eigen::RowMajor>::InnerIterator;

// One observation's coupling W = J_pose^T J_point between keyframe block k and landmark l.
struct Coupling {
  int keyframe = 0;
  Matrix63d W;
};

// V^-1 if V passes the degenerate-landmark rule, else false.
bool invertLandmarkBlock(const Eigen::Matrix3d& V, double min_relative_eigenvalue,
                         Eigen::Matrix3d* V_inv) {
  if (!V.allFinite()) return false;
  Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eig;
  eig.computeDirect(V);
  const Eigen::Vector3d lambda = eig.eigenvalues();  // increasing
  if (!(lambda[2] > 0.0) || !(lambda[0] > min_relative_eigenvalue * lambda[2])) return false;
  *V_inv = eig.eigenvectors() * lambda.cwiseInverse().asDiagonal() * eig.eigenvectors().transpose();
  return true;
}

}  // namespace

std::string validate(const ReducedCameraMatrixConfig& config) {
  if (!(config.landmark_min_relative_eigenvalue >= 0.0 &&
        config.landmark_min_relative_eigenvalue < 1.0)) {
    return "landmark_min_relative_eigenvalue must be in [0, 1)";
  }
  return {};
}

ReducedCameraMatrix reduceCameraMatrix(const BaLinearization& lin,
                                       const ReducedCameraMatrixConfig& config) {
  if (const std::string e = validate(config); !e.empty()) {
    throw std::invalid_argument("reduceCameraMatrix: config: " + e);
  }
  const int K = static_cast<int>(lin.keyframe_ids.size());
  const int L = static_cast<int>(lin.landmark_ids.size());
  const int P = lin.numPoseColumns();
  if (lin.jacobian.cols() != lin.landmarkColumn(L)) {
    throw std::invalid_argument("reduceCameraMatrix: the Jacobian has " +
                                std::to_string(lin.jacobian.cols()) + " columns, expected " +
                                std::to_string(lin.landmarkColumn(L)));
  }

  // Pass 1: the landmark blocks V and the degenerate-landmark rule.
  std::vector<Eigen::Matrix3d> V(L, Eigen::Matrix3d::Zero());
  std::vector<int> pose_block(lin.jacobian.rows(), -1);
  std::vector<int> landmark_block(lin.jacobian.rows(), -1);
  for (int row = 0; row < lin.jacobian.rows(); ++row) {
    Eigen::Vector3d b = Eigen::Vector3d::Zero();
    for (RowIterator it(lin.jacobian, row); it; ++it) {
      const int col = static_cast<int>(it.col());
      if (col < P) {
        pose_block[row] = col / 6;
      } else {
        landmark_block[row] = (col - P) / 3;
        b[(col - P) % 3] = it.value();
      }
    }
    if (landmark_block[row] >= 0) V[landmark_block[row]].noalias() += b * b.transpose();
  }
  std::vector<Eigen::Matrix3d> V_inv(L);
  std::vector<std::uint8_t> kept(L, 0);
  ReducedCameraMatrix S;
  for (int l = 0; l < L; ++l) {
    kept[l] = invertLandmarkBlock(V[l], config.landmark_min_relative_eigenvalue, &V_inv[l]);
    if (!kept[l]) S.dropped_landmark_ids.push_back(lin.landmark_ids[l]);
  }

  // Pass 2 over the rows of kept landmarks: diagonal pose blocks of H and, per observation
  // (run of consecutive rows with the same keyframe and landmark), its coupling W.
  std::vector<Matrix6d> diag(K, Matrix6d::Zero());
  std::vector<int> coupling_landmark;
  std::vector<Coupling> couplings;
  couplings.reserve(lin.jacobian.rows() / 2 + 1);
  coupling_landmark.reserve(lin.jacobian.rows() / 2 + 1);
  for (int row = 0; row < lin.jacobian.rows(); ++row) {
    const int k = pose_block[row];
    const int l = landmark_block[row];
    if (k < 0 || l < 0 || !kept[l]) continue;  // fixed keyframe: constrains the landmark only
    Eigen::Matrix<double, 6, 1> a = Eigen::Matrix<double, 6, 1>::Zero();
    Eigen::Vector3d b = Eigen::Vector3d::Zero();
    for (RowIterator it(lin.jacobian, row); it; ++it) {
      const int col = static_cast<int>(it.col());
      if (col < P) {
        a[col % 6] = it.value();
      } else {
        b[(col - P) % 3] = it.value();
      }
    }
    diag[k].noalias() += a * a.transpose();
    if (couplings.empty() || coupling_landmark.back() != l || couplings.back().keyframe != k) {
      couplings.push_back(Coupling{k, Matrix63d::Zero()});
      coupling_landmark.push_back(l);
    }
    couplings.back().W.noalias() += a * b.transpose();
  }

  // Bucket the couplings by landmark (counting sort, stable).
  std::vector<int> start(L + 1, 0);
  for (const int l : coupling_landmark) ++start[l + 1];
  for (int l = 0; l < L; ++l) start[l + 1] += start[l];
  std::vector<int> order(couplings.size());
  {
    std::vector<int> next(start.begin(), start.end() - 1);
    for (size_t c = 0; c < couplings.size(); ++c) order[next[coupling_landmark[c]]++] = c;
  }

  // Per landmark: subtract W_a V^-1 W_b^T from block (a, b) for a <= b.
  absl::flat_hash_map<std::uint64_t, int> off_index;  // key a * K + b (a < b)
  std::vector<Matrix6d> off_blocks;
  std::vector<std::pair<int, int>> off_keys;
  std::vector<std::pair<int, Matrix63d>> obs;  // (keyframe, W) of one landmark, merged
  std::vector<Matrix63d> Y;
  for (int l = 0; l < L; ++l) {
    if (!kept[l]) continue;
    obs.clear();
    for (int c = start[l]; c < start[l + 1]; ++c) {
      const Coupling& cp = couplings[order[c]];
      obs.emplace_back(cp.keyframe, cp.W);
    }
    std::sort(obs.begin(), obs.end(),
              [](const auto& x, const auto& y) { return x.first < y.first; });
    size_t m = 0;  // merge repeated keyframes
    for (size_t c = 0; c < obs.size(); ++c) {
      if (m > 0 && obs[m - 1].first == obs[c].first) {
        obs[m - 1].second += obs[c].second;
      } else {
        obs[m++] = obs[c];
      }
    }
    obs.resize(m);
    Y.resize(m);
    for (size_t x = 0; x < m; ++x) Y[x].noalias() = obs[x].second * V_inv[l];
    for (size_t x = 0; x < m; ++x) {
      const int a = obs[x].first;
      diag[a].noalias() -= Y[x] * obs[x].second.transpose();
      for (size_t y = x + 1; y < m; ++y) {
        const int b = obs[y].first;
        const std::uint64_t key = static_cast<std::uint64_t>(a) * K + b;
        auto [it, inserted] = off_index.try_emplace(key, static_cast<int>(off_blocks.size()));
        if (inserted) {
          off_blocks.push_back(Matrix6d::Zero());
          off_keys.emplace_back(a, b);
        }
        off_blocks[it->second].noalias() -= Y[x] * obs[y].second.transpose();
      }
    }
  }

  // The diagonal blocks were accumulated as full 6x6 matrices: symmetrise them exactly.
  for (Matrix6d& d : diag) d = (0.5 * (d + d.transpose())).eval();

  // Block columns: (row block, block index, transposed?), sorted by row block.
  struct Entry {
    int row;
    const Matrix6d* block;
    bool transposed;
  };
  std::vector<std::vector<Entry>> columns(K);
  for (int k = 0; k < K; ++k) columns[k].push_back(Entry{k, &diag[k], false});
  for (size_t o = 0; o < off_blocks.size(); ++o) {
    const auto [a, b] = off_keys[o];
    columns[b].push_back(Entry{a, &off_blocks[o], false});  // block (a, b)
    columns[a].push_back(Entry{b, &off_blocks[o], true});   // block (b, a) = (a, b)^T
  }
  S.block_col_ptr.assign(K + 1, 0);
  for (int k = 0; k < K; ++k) {
    std::sort(columns[k].begin(), columns[k].end(),
              [](const Entry& x, const Entry& y) { return x.row < y.row; });
    S.block_col_ptr[k + 1] = S.block_col_ptr[k] + static_cast<int>(columns[k].size());
  }
  S.block_row_index.reserve(S.block_col_ptr[K]);
  for (int k = 0; k < K; ++k) {
    for (const Entry& e : columns[k]) S.block_row_index.push_back(e.row);
  }

  // Scalar CSC, written directly.
  const Eigen::Index nnz = 36 * static_cast<Eigen::Index>(S.block_col_ptr[K]);
  S.matrix.resize(P, P);
  S.matrix.resizeNonZeros(nnz);
  int* outer = S.matrix.outerIndexPtr();
  int* inner = S.matrix.innerIndexPtr();
  double* values = S.matrix.valuePtr();
  int p = 0;
  for (int k = 0; k < K; ++k) {
    for (int q = 0; q < 6; ++q) {
      outer[6 * k + q] = p;
      for (const Entry& e : columns[k]) {
        for (int r = 0; r < 6; ++r) {
          inner[p] = 6 * e.row + r;
          values[p] = e.transposed ? (*e.block)(q, r) : (*e.block)(r, q);
          ++p;
        }
      }
    }
  }
  outer[P] = p;
  S.keyframe_ids = lin.keyframe_ids;
  S.block_of_id.reserve(K);
  for (int k = 0; k < K; ++k) S.block_of_id.emplace(lin.keyframe_ids[k], k);
  return S;
}

}  // namespace cblox
