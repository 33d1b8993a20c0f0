#pragma once

// FUZZ_CHECK(condition, message): a property a parser promises on success (e.g. a mesh it
// returns passes Mesh::validate()); when it does not hold, prints the message and aborts, so
// libFuzzer (and the replay ctest) reports the input as a crash.

#include <cstdio>
#include <cstdlib>
#include <string>

#define FUZZ_CHECK(condition, message)                                                           \
  do {                                                                                           \
    if (!(condition)) {                                                                          \
      std::fprintf(stderr, "%s:%d: FUZZ_CHECK(%s) failed: %s\n", __FILE__, __LINE__, #condition, \
                   std::string(message).c_str());                                                \
      std::abort();                                                                              \
    }                                                                                            \
  } while (false)
