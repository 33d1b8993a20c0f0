#pragma once

// Command-line helper shared by the bench programs.

#include <cstdio>
#include <cstdlib>
#include <string>

namespace cblox {

/// The value that follows the flag argv[*i], advancing *i to it; prints "<flag> needs a
/// value" and exits with status 2 when there is none.
inline std::string flagValue(int argc, char** argv, int* i) {
  if (*i + 1 >= argc) {
    std::fprintf(stderr, "%s needs a value\n", argv[*i]);
    std::exit(2);
  }
  return argv[++*i];
}

}  // namespace cblox
