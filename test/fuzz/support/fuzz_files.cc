// Scratch files for the fuzz targets (fuzz_files.h).

#include "test/fuzz/support/fuzz_files.h"

#include <unistd.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <stdexcept>

namespace cblox::fuzz {
namespace fs = std::filesystem;

std::vector<std::string> splitParts(const uint8_t* data, size_t size, size_t count) {
  const std::string_view input(reinterpret_cast<const char*>(data), size);
  std::vector<std::string> parts;
  size_t begin = 0;
  while (parts.size() + 1 < count) {
    const size_t end = input.find(kPartSeparator, begin);
    if (end == std::string_view::npos) break;
    parts.emplace_back(input.substr(begin, end - begin));
    begin = end + kPartSeparator.size();
  }
  parts.emplace_back(begin <= input.size() ? input.substr(begin) : std::string_view());
  parts.resize(count);
  return parts;
}

namespace {

// Owns the directory: removed when the process exits normally.
struct ScratchDir {
  std::string path;
  ScratchDir() {
    const char* tmp = std::getenv("TMPDIR");
    std::string pattern =
        std::string(tmp != nullptr && *tmp != '\0' ? tmp : "/tmp") + "/cblox-fuzz-XXXXXX";
    if (::mkdtemp(pattern.data()) == nullptr) {
      throw std::runtime_error("cannot create a scratch directory from " + pattern);
    }
    path = pattern;
  }
  ~ScratchDir() {
    std::error_code ec;
    fs::remove_all(path, ec);
  }
};

}  // namespace

const std::string& freshScratchDir() {
  static const ScratchDir dir;
  std::error_code ec;
  for (const fs::directory_entry& entry : fs::directory_iterator(dir.path)) {
    fs::remove_all(entry.path(), ec);
  }
  return dir.path;
}

void writeScratchFile(const std::string& dir, const std::string& relative, std::string_view bytes) {
  const fs::path path = fs::path(dir) / relative;
  fs::create_directories(path.parent_path());
  std::ofstream out(path, std::ios::binary | std::ios::trunc);
  out.write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
  if (!out) throw std::runtime_error("cannot write scratch file " + path.string());
}

}  // namespace cblox::fuzz
