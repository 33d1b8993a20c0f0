#pragma once

#include <cstdio>
#include <exception>

#include "daemon/config/yaml_config.h"

namespace cblox {

/// Runs a process's body and turns what escapes it into the exit statuses every cblox
/// process documents: ConfigError (usage or configuration) -> 2, any other exception
/// (runtime error) -> 1, each with one line on stderr naming the process. `body` returns
/// the exit status. Call from main(); not for library code.
template <typename Body>
int runProcess(const char* name, Body&& body) {
  try {
    return body();
  } catch (const ConfigError& e) {
    std::fprintf(stderr, "%s: configuration error: %s\n", name, e.what());
    return 2;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "%s: error: %s\n", name, e.what());
    return 1;
  }
}

}  // namespace cblox
