#pragma once

#include <span>
#include <string>
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

/// Nested dissection (METIS_NodeND through cholmod_metis, followed by an elimination-tree
/// postorder) on the block pattern. On a loop's pattern it gives a shallower elimination
/// tree than AMD: a keyframe's path to the root crosses one separator per level instead of
/// the long chains AMD builds along a band, so a sparse forward solve (SparseSolve-
/// CovarianceSolver) reaches fewer columns (synthetic 2-lap loop, 500 keyframes: 582 instead
/// of 1008 of 2994 columns, 1.64 instead of 3.10 Mflop; BENCHMARKS.md). METIS is seeded
/// deterministically: the same S gives the same permutation. CHOLMOD may fall back to AMD
/// where METIS would need too much memory (Common->metis_memory) or for nearly dense
/// patterns (Common->metis_dswitch). Throws std::runtime_error if ordering fails. Thread-safe
/// (its own cholmod_common).
std::vector<int> blockNestedDissectionOrdering(const ReducedCameraMatrix& S);

/// Which fill-reducing ordering of the block pattern a solver uses.
enum class BlockOrdering {
  kAmd,               ///< blockAmdOrdering
  kNestedDissection,  ///< blockNestedDissectionOrdering
};

/// "amd" | "nested_dissection".
const char* blockOrderingName(BlockOrdering ordering);
/// Parses blockOrderingName's names; false (and `ordering` untouched) for anything else.
bool parseBlockOrdering(const std::string& name, BlockOrdering* ordering);
/// The chosen ordering's permutation. Throws std::invalid_argument for a value outside the
/// enum and what the ordering throws.
std::vector<int> blockOrdering(const ReducedCameraMatrix& S, BlockOrdering ordering);

/// Scalar permutation of a block permutation with 6x6 blocks: scalar[6k + q] =
/// 6 * block_perm[k] + q (order within a block kept). Thread-safe (pure).
std::vector<int> expandBlockPermutation(std::span<const int> block_perm);

}  // namespace cblox
