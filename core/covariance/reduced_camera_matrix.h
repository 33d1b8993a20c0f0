#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include <absl/container/flat_hash_map.h>
#include <Eigen/SparseCore>

#include "core/optimization/ba_linearization.h"

namespace cblox {

/// The reduced camera matrix of a bundle-adjustment linearization: the Schur complement of
/// the landmarks in the information matrix H = J^T J,
///   S = H_pp - H_pl H_ll^-1 H_lp,
/// the information matrix of the free keyframes' tangents with the landmarks marginalised.
///
/// Layout: K = keyframe_ids.size() column blocks of 6, in the order of
/// BaLinearization::keyframe_ids; block k's tangent is [rho (m); phi (rad)], the left
/// perturbation T_C_G <- exp(delta) * T_C_G of SE3Manifold (equal, up to sign, to the right
/// perturbation of T_G_C, so covariances are the same). Units of S: (weighted pixels)^2 per
/// m^2, per m*rad and per rad^2 (the rows are unit-information residuals). S^-1 is the
/// covariance of the keyframe tangents (m^2, m*rad, rad^2). The fixed keyframes of the BA
/// have no block: they fix the gauge.
struct ReducedCameraMatrix {
  /// 6K x 6K, symmetric with BOTH triangles stored, column-major, compressed, sorted rows.
  /// Its pattern is block-sparse: every stored 6x6 block is stored densely (36 entries).
  Eigen::SparseMatrix<double> matrix;
  /// Caller's keyframe id of each block (BaLinearization::keyframe_ids).
  std::vector<std::uint64_t> keyframe_ids;
  /// Block pattern, compressed by column (K + 1 pointers), both triangles and the diagonal,
  /// rows sorted: block (r, c) is stored iff keyframes r and c observe a common landmark
  /// (or r == c).
  std::vector<int> block_col_ptr;
  std::vector<int> block_row_index;
  /// Ids of the landmarks left out (all their rows, also their H_pp part) by the
  /// degenerate-landmark rule (see
  /// ReducedCameraMatrixConfig), in linearization order.
  std::vector<std::uint64_t> dropped_landmark_ids;

  /// Number of keyframe blocks K. Thread-safe.
  int numBlocks() const { return static_cast<int>(keyframe_ids.size()); }
  /// Block index of a keyframe id, or -1 if the id has no block (fixed, culled or unknown).
  /// Thread-safe (const).
  int blockOf(std::uint64_t keyframe_id) const {
    const auto it = block_of_id.find(keyframe_id);
    return it == block_of_id.end() ? -1 : it->second;
  }

  /// keyframe id -> block index.
  absl::flat_hash_map<std::uint64_t, int> block_of_id;
};

struct ReducedCameraMatrixConfig {
  /// Degenerate-landmark rule: a landmark whose 3x3 information block H_ll (metres^-2) has
  /// lambda_min <= landmark_min_relative_eigenvalue * lambda_max (or lambda_max <= 0, or a
  /// non-finite entry) is left out of S entirely, as if it had no observations: e.g. a
  /// landmark seen by a single mono observation (rank 2) or by rays with no parallax.
  /// Dropping information is conservative (S only loses a positive semi-definite term, so
  /// covariances only grow). The dropped ids are listed in the result. Default 1e-10;
  /// must be in [0, 1).
  double landmark_min_relative_eigenvalue = 1e-10;
};

/// Empty if valid, else a message naming the bad field. Thread-safe (pure).
std::string validate(const ReducedCameraMatrixConfig& config);

/// Forms S from the linearization's Jacobian without forming H: per landmark, its 3x3 block
/// V, V^-1, and the outer products W_a V^-1 W_b^T over the pairs of keyframes (a, b) that
/// observe it (O(sum of squared observation counts); measured with cblox-bench-covariance's
/// loop scenes: ~90 ms at 500 keyframes / 25k landmarks, ~200 ms at 1000 / 50k). Keyframe blocks
/// with no landmark left still get their (possibly singular) diagonal block; singularity is
/// detected when a solver factorises S. Throws std::invalid_argument if the config is invalid or
/// the linearization is malformed (Jacobian columns not matching its id lists). Thread-safe (pure).
ReducedCameraMatrix reduceCameraMatrix(const BaLinearization& linearization,
                                       const ReducedCameraMatrixConfig& config = {});

}  // namespace cblox
