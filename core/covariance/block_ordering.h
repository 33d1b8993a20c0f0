#pragma once

#include <span>
#include <vector>

#include "core/covariance/reduced_camera_matrix.h"

namespace cblox {

/// Fill-reducing orderings of the reduced camera matrix, computed on its K x K block
/// pattern (36x fewer entries than the scalar pattern) and expanded to scalars. A block
/// permutation p lists blocks in pivot order: p[k] is the block eliminated k-th.

/// Constrained approximate minimum degree (SuiteSparse camd_order): blocks with a lower
/// constraint[b] come first, so the blocks of the highest set are eliminated last (e.g.
/// others 0, keyframe i 1, keyframe j 2 puts i second to last and j last). constraint has
/// one entry in [0, K) per block. Throws std::invalid_argument on a bad constraint vector
/// and std::runtime_error if CAMD fails. Thread-safe (pure).
std::vector<int> constrainedBlockOrdering(const ReducedCameraMatrix& S,
                                          std::span<const int> constraint);

/// Unconstrained approximate minimum degree (SuiteSparse amd_order) on the block pattern.
/// Throws std::runtime_error if AMD fails. Thread-safe (pure).
std::vector<int> blockAmdOrdering(const ReducedCameraMatrix& S);

/// Scalar permutation of a block permutation with 6x6 blocks: scalar[6k + q] =
/// 6 * block_perm[k] + q (order within a block kept). Thread-safe (pure).
std::vector<int> expandBlockPermutation(std::span<const int> block_perm);

}  // namespace cblox
