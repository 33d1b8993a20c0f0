// A main for the fuzz targets in the normal (gcc, no libFuzzer) build: runs the target's
// LLVMFuzzerTestOneInput once on every file named on the command line, or in a folder named
// there (not recursive), in name order; a path that does not exist (a target without
// regressions) holds no inputs. Exit status 0 when every input ran, 1 when a folder or file
// cannot be read; a crash or an escaped exception ends the run as it would the
// fuzzer. Used by the ctests fuzz.<target> over test/fuzz/corpus/<target> and
// test/fuzz/regressions/<target>.

#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <string>
#include <vector>

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size);
extern "C" __attribute__((weak)) int LLVMFuzzerInitialize(int* argc, char*** argv);

namespace {
namespace fs = std::filesystem;

bool runFile(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) {
    std::fprintf(stderr, "replay: cannot read %s\n", path.c_str());
    return false;
  }
  const std::vector<char> bytes((std::istreambuf_iterator<char>(in)),
                                std::istreambuf_iterator<char>());
  std::fprintf(stderr, "replay: %s (%zu bytes)\n", path.c_str(), bytes.size());
  LLVMFuzzerTestOneInput(reinterpret_cast<const uint8_t*>(bytes.data()), bytes.size());
  return true;
}

}  // namespace

int main(int argc, char** argv) {
  if (LLVMFuzzerInitialize != nullptr) LLVMFuzzerInitialize(&argc, &argv);
  bool ok = true;
  size_t inputs = 0;
  for (int i = 1; i < argc; ++i) {
    const fs::path arg(argv[i]);
    std::error_code ec;
    if (!fs::exists(arg, ec)) {
      std::fprintf(stderr, "replay: %s does not exist (no inputs there)\n", arg.c_str());
      continue;
    }
    if (!fs::is_directory(arg, ec)) {
      ok = runFile(arg) && ok;
      ++inputs;
      continue;
    }
    std::vector<fs::path> files;
    for (const fs::directory_entry& entry : fs::directory_iterator(arg, ec)) {
      if (entry.is_regular_file()) files.push_back(entry.path());
    }
    if (ec) {
      std::fprintf(stderr, "replay: cannot list %s: %s\n", arg.c_str(), ec.message().c_str());
      ok = false;
    }
    std::sort(files.begin(), files.end());
    for (const fs::path& file : files) {
      ok = runFile(file) && ok;
      ++inputs;
    }
  }
  std::printf("replay: %zu inputs %s\n", inputs, ok ? "ran" : "ran, some unreadable");
  return ok ? 0 : 1;
}
