// Fuzz target: config/tracker.yaml's loader (loadTrackerConfig, with its validation) on any
// bytes.

#include <cstddef>
#include <cstdint>

#include "daemon/tracker/tracker_config.h"
#include "test/fuzz/support/fuzz_config.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  (void)cblox::fuzz::loadConfigInput<cblox::TrackerProcessConfig>(data, size,
                                                                  cblox::loadTrackerConfig);
  return 0;
}
