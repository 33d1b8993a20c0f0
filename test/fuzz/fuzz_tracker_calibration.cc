// Fuzz target: the tracker's calibration file (loadCalibrationFile,
// daemon/tracker/calibration_file.h) on any bytes, for stereo and for RGB-D. The loader documents
// ConfigError as its only failure; anything else escapes as a crash.

#include <cstddef>
#include <cstdint>
#include <string>

#include "daemon/common/yaml_config.h"
#include "daemon/tracker/calibration_file.h"
#include "test/fuzz/support/fuzz_files.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  using namespace cblox::fuzz;
  const std::string& dir = freshScratchDir();
  writeScratchFile(dir, "camchain.yaml", {reinterpret_cast<const char*>(data), size});
  for (const bool stereo : {true, false}) {
    try {
      (void)cblox::loadCalibrationFile(dir + "/camchain.yaml", stereo);
    } catch (const cblox::ConfigError&) {
    }
  }
  return 0;
}
