#pragma once

#include <cstdlib>
#include <functional>
#include <initializer_list>
#include <string>

#include "daemon/common/yaml_config.h"

namespace cblox {

/// The command-line walk shared by the processes: `--help` / `-h` call `on_help` and exit 0;
/// a flag listed in `switches` takes no value and calls `on_switch(flag)`; every other flag
/// takes the next argument as its value and calls `on_value(flag, value)`, which returns
/// false for a flag it does not know. Throws ConfigError naming the flag for a missing value
/// or an unknown flag. Thread-safe (no shared state).
inline void parseFlags(int argc, char** argv, const std::function<void()>& on_help,
                       std::initializer_list<const char*> switches,
                       const std::function<void(const std::string&)>& on_switch,
                       const std::function<bool(const std::string&, const std::string&)>& on_value) {
  for (int i = 1; i < argc; ++i) {
    const std::string flag = argv[i];
    if (flag == "--help" || flag == "-h") {
      on_help();
      std::exit(0);
    }
    bool is_switch = false;
    for (const char* s : switches) is_switch = is_switch || flag == s;
    if (is_switch) {
      on_switch(flag);
      continue;
    }
    if (i + 1 >= argc) throw ConfigError(flag + ": missing value (see --help)");
    if (!on_value(flag, argv[++i])) throw ConfigError("unknown option '" + flag + "' (see --help)");
  }
}

}  // namespace cblox
