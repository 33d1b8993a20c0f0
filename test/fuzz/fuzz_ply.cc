// Fuzz target: readPly (core/io/ply_io.h) on any bytes. A mesh it accepts must be valid.

#include <cstddef>
#include <cstdint>
#include <string>
#include <string_view>

#include "core/io/ply_io.h"
#include "test/fuzz/support/fuzz_check.h"
#include "test/fuzz/support/fuzz_files.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const std::string& dir = cblox::fuzz::freshScratchDir();
  cblox::fuzz::writeScratchFile(dir, "in.ply", {reinterpret_cast<const char*>(data), size});
  cblox::Mesh mesh;
  std::string error;
  if (cblox::readPly(dir + "/in.ply", &mesh, &error))
    FUZZ_CHECK(mesh.validate().empty(), mesh.validate());
  return 0;
}
