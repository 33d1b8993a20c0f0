// Fuzz target: config/mapper.yaml's loader (loadMapperConfig), then validate() as
// cblox-mapper does, on any bytes.

#include <cstddef>
#include <cstdint>
#include <optional>

#include "daemon/mapper/mapper_config_loader.h"
#include "test/fuzz/support/fuzz_config.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const std::optional<cblox::MapperProcessConfig> config =
      cblox::fuzz::loadConfigInput<cblox::MapperProcessConfig>(data, size, cblox::loadMapperConfig);
  if (config) (void)config->validate();
  return 0;
}
