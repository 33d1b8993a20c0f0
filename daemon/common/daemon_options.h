#pragma once

// The command-line options every daemon (cblox-capture, cblox-tracker, cblox-mapper) shares:
// --config FILE, --lcm-url URL and --quiet, and the process config they give.

#include <optional>
#include <string>

#include <CLI/CLI.hpp>

#include "daemon/common/cli.h"
#include "daemon/common/yaml_config.h"

namespace cblox {

struct DaemonOptions {
  std::optional<std::string> config_file;  ///< --config: the process's YAML settings
  std::optional<std::string> lcm_url;      ///< --lcm-url: instead of the config's lcm_url
  bool quiet = false;                      ///< --quiet: no start-up and progress lines
};

/// Adds --config, --lcm-url and --quiet to `app`, writing into *options (which must outlive
/// the parse). `config_example` names the shipped settings file, e.g. "config/mapper.yaml".
inline void addDaemonOptions(CLI::App& app, DaemonOptions* options,
                             const std::string& config_example) {
  app.add_option("--config", options->config_file,
                 "settings file (YAML, as " + config_example + "); default: built-in settings")
      ->type_name("FILE");
  app.add_option("--lcm-url", options->lcm_url,
                 "LCM URL instead of the settings' lcm_url (empty: LCM's default)")
      ->type_name("URL");
  app.add_flag("--quiet", options->quiet, "no start-up and progress lines on stdout");
}

/// The process config: `load` (YAML root -> Config, throws ConfigError) applied to the --config
/// file, or Config's defaults without one; then --lcm-url. Throws ConfigError for a file that
/// cannot be read or parsed, and for a YAML::Exception that escapes `load` (a value of the
/// wrong shape that a loader converts directly, e.g. a list where it reads a number).
template <typename Config, typename Load>
Config loadDaemonConfig(const DaemonOptions& options, Load load) {
  Config config{};
  if (options.config_file) {
    const YAML::Node root = loadYamlFile(*options.config_file);
    try {
      config = load(root);
    } catch (const YAML::Exception& e) {
      throw ConfigError(*options.config_file + ": " + e.what());
    }
  }
  if (options.lcm_url) config.lcm_url = *options.lcm_url;
  return config;
}

}  // namespace cblox
