#include "core/covariance/block_ordering.h"

#include <stdexcept>
#include <string>

#include <amd.h>
#include <camd.h>
#include <cholmod.h>

#include "core/optimization/cholmod_support.h"

namespace cblox {

std::vector<int> constrainedBlockOrdering(const ReducedCameraMatrix& S,
                                          std::span<const int> constraint) {
  const int K = S.numBlocks();
  if (static_cast<int>(constraint.size()) != K) {
    throw std::invalid_argument("constrainedBlockOrdering: " + std::to_string(constraint.size()) +
                                " constraints for " + std::to_string(K) + " blocks");
  }
  for (const int c : constraint) {
    if (c < 0 || c >= K) {
      throw std::invalid_argument("constrainedBlockOrdering: constraint set " + std::to_string(c) +
                                  " outside [0, " + std::to_string(K) + ")");
    }
  }
  std::vector<int> perm(K);
  if (K == 0) return perm;
  double control[CAMD_CONTROL];
  camd_defaults(control);
  const int status = camd_order(K, S.block_col_ptr.data(), S.block_row_index.data(), perm.data(),
                                control, nullptr, constraint.data());
  if (status != CAMD_OK && status != CAMD_OK_BUT_JUMBLED) {
    throw std::runtime_error("constrainedBlockOrdering: camd_order failed with status " +
                             std::to_string(status));
  }
  return perm;
}

std::vector<int> blockAmdOrdering(const ReducedCameraMatrix& S) {
  const int K = S.numBlocks();
  std::vector<int> perm(K);
  if (K == 0) return perm;
  double control[AMD_CONTROL];
  amd_defaults(control);
  const int status =
      amd_order(K, S.block_col_ptr.data(), S.block_row_index.data(), perm.data(), control, nullptr);
  if (status != AMD_OK && status != AMD_OK_BUT_JUMBLED) {
    throw std::runtime_error("blockAmdOrdering: amd_order failed with status " +
                             std::to_string(status));
  }
  return perm;
}

std::vector<int> blockNestedDissectionOrdering(const ReducedCameraMatrix& S) {
  const int K = S.numBlocks();
  std::vector<int> perm(K);
  if (K == 0) return perm;
  // A pattern-only view of the block pattern: both triangles are stored, and a view with
  // stype 1 ignores the lower one. CHOLMOD does not modify its input.
  cholmod_sparse pattern = cholmodUpperView(K, const_cast<int*>(S.block_col_ptr.data()),
                                            const_cast<int*>(S.block_row_index.data()), nullptr);
  pattern.xtype = CHOLMOD_PATTERN;
  CholmodCommon common;
  if (!cholmod_metis(&pattern, nullptr, 0, /*postorder=*/1, perm.data(), common.get()) ||
      common.get()->status < CHOLMOD_OK) {
    throw std::runtime_error("blockNestedDissectionOrdering: cholmod_metis failed with status " +
                             std::to_string(common.get()->status));
  }
  return perm;
}

const char* blockOrderingName(BlockOrdering ordering) {
  return ordering == BlockOrdering::kAmd ? "amd" : "nested_dissection";
}

bool parseBlockOrdering(const std::string& name, BlockOrdering* ordering) {
  if (name == "amd") {
    *ordering = BlockOrdering::kAmd;
  } else if (name == "nested_dissection") {
    *ordering = BlockOrdering::kNestedDissection;
  } else {
    return false;
  }
  return true;
}

std::vector<int> blockOrdering(const ReducedCameraMatrix& S, BlockOrdering ordering) {
  switch (ordering) {
    case BlockOrdering::kAmd:
      return blockAmdOrdering(S);
    case BlockOrdering::kNestedDissection:
      return blockNestedDissectionOrdering(S);
  }
  throw std::invalid_argument("blockOrdering: not a BlockOrdering value");
}

std::vector<int> expandBlockPermutation(std::span<const int> block_perm) {
  std::vector<int> perm(6 * block_perm.size());
  for (size_t k = 0; k < block_perm.size(); ++k) {
    for (int q = 0; q < 6; ++q) perm[6 * k + q] = 6 * block_perm[k] + q;
  }
  return perm;
}

}  // namespace cblox
