#pragma once

// The config fuzz targets' common step: the input becomes the --config file and goes through
// loadDaemonConfig (daemon/common/daemon_options.h) with the process's loader, as the
// process's main does. A loader documents ConfigError as its only failure (exit status 2);
// any other exception escapes to the fuzzer as a crash.

#include <cstddef>
#include <cstdint>
#include <optional>
#include <string>

#include "daemon/common/daemon_options.h"
#include "daemon/common/yaml_config.h"
#include "test/fuzz/support/fuzz_files.h"

namespace cblox::fuzz {

/// `load`'s Config from the input as a config file, or std::nullopt on ConfigError.
template <typename Config, typename Load>
std::optional<Config> loadConfigInput(const uint8_t* data, size_t size, Load load) {
  const std::string& dir = freshScratchDir();
  writeScratchFile(dir, "config.yaml", {reinterpret_cast<const char*>(data), size});
  DaemonOptions options;
  options.config_file = dir + "/config.yaml";
  try {
    return loadDaemonConfig<Config>(options, load);
  } catch (const ConfigError&) {
    return std::nullopt;
  }
}

}  // namespace cblox::fuzz
