// Fuzz target: readTextMatrix (core/io/text_matrix.h) as the dataset readers call it: a 3x3
// intrinsics matrix or a 4x4 pose (then validateRigidTransform). The first byte chooses.

#include <cstddef>
#include <cstdint>
#include <optional>
#include <string>

#include <Eigen/Core>

#include "core/io/text_matrix.h"
#include "test/fuzz/support/fuzz_files.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  if (size == 0) return 0;
  const int n = data[0] % 2 == 0 ? 3 : 4;
  const std::string& dir = cblox::fuzz::freshScratchDir();
  cblox::fuzz::writeScratchFile(dir, "in.txt", {reinterpret_cast<const char*>(data) + 1, size - 1});
  std::string error;
  const std::optional<Eigen::MatrixXd> m = cblox::readTextMatrix(dir + "/in.txt", n, n, &error);
  if (m && n == 4) (void)cblox::validateRigidTransform(Eigen::Matrix4d(*m));
  return 0;
}
