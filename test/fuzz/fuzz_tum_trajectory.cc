// Fuzz target: readTumTrajectory (core/io/tum_trajectory.h) on any bytes, then
// interpolatePose at the first, a middle and past the last stamp of what it accepts.

#include <cstddef>
#include <cstdint>
#include <optional>
#include <string>

#include "core/io/tum_trajectory.h"
#include "test/fuzz/support/fuzz_files.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const std::string& dir = cblox::fuzz::freshScratchDir();
  cblox::fuzz::writeScratchFile(dir, "in.txt", {reinterpret_cast<const char*>(data), size});
  std::string error;
  const std::optional<cblox::StampedTrajectory> trajectory =
      cblox::readTumTrajectory(dir + "/in.txt", &error);
  if (!trajectory || trajectory->empty()) return 0;
  const double first = trajectory->front().timestamp_s;
  const double last = trajectory->back().timestamp_s;
  for (const double t : {first, 0.5 * (first + last), last + 1.0}) {
    (void)cblox::interpolatePose(*trajectory, t, 0.1);
  }
  return 0;
}
