// Fuzz target: config/capture.yaml's loader (loadCaptureConfig) on any bytes.

#include <cstddef>
#include <cstdint>

#include "daemon/capture/capture_config.h"
#include "test/fuzz/support/fuzz_config.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  (void)cblox::fuzz::loadConfigInput<cblox::CaptureConfig>(data, size, cblox::loadCaptureConfig);
  return 0;
}
