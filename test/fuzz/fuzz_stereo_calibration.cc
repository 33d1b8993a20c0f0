// Fuzz target: loadStereoCalibration (drivers/calibration/calibration_file.h), Kalibr
// camchain or OpenCV YAML/XML by content, on the input's first part (split at "\n@@@@\n",
// fuzz_files.h); a second part, when not empty, is the extrinsics.yml beside it. Read as a
// stereo pair and as a left camera only. The loader documents CalibrationError as its only
// failure; anything else escapes as a crash.

#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include "drivers/calibration/calibration_file.h"
#include "test/fuzz/support/fuzz_files.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  using namespace cblox::fuzz;
  const std::vector<std::string> parts = splitParts(data, size, 2);
  const std::string& dir = freshScratchDir();
  writeScratchFile(dir, "calibration.yaml", parts[0]);
  if (!parts[1].empty()) writeScratchFile(dir, "extrinsics.yml", parts[1]);
  for (const bool stereo : {true, false}) {
    try {
      (void)cblox::loadStereoCalibration(dir + "/calibration.yaml", stereo);
    } catch (const cblox::CalibrationError&) {
    }
  }
  return 0;
}
