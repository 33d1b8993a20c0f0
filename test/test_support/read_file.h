#pragma once

#include <cstdio>
#include <string>

namespace cblox::test {

/// The whole content of the file at `path` (empty when it cannot be opened).
inline std::string readFile(const std::string& path) {
  std::string content;
  if (std::FILE* f = std::fopen(path.c_str(), "rb")) {
    char buffer[4096];
    size_t n;
    while ((n = std::fread(buffer, 1, sizeof(buffer), f)) > 0) content.append(buffer, n);
    std::fclose(f);
  }
  return content;
}

}  // namespace cblox::test
