// Fuzz target: loadMap (core/persistence/map_store.h) on a map directory made of the input's
// parts (split at "\n@@@@\n", fuzz_files.h): the first part is the manifest's payload, sealed
// here with a valid header and checksum (so the fuzzer reaches the restore of what the
// manifest lists); every further part is "<file name>\n<the file's bytes>", written as is.

#include <cstddef>
#include <cstdint>
#include <memory>
#include <stdexcept>
#include <string>
#include <vector>

#include "core/persistence/map_file_header.h"
#include "core/persistence/map_manifest.h"
#include "core/persistence/map_store.h"
#include "test/fuzz/support/fuzz_files.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const std::vector<std::string> parts = cblox::fuzz::splitParts(data, size, 8);
  const std::string& dir = cblox::fuzz::freshScratchDir();
  cblox::fuzz::writeScratchFile(
      dir, "manifest.cbmap",
      cblox::sealMapFile(cblox::kManifestFileMagic, cblox::kManifestVersion, parts[0]));
  for (size_t i = 1; i < parts.size(); ++i) {
    const size_t newline = parts[i].find('\n');
    if (newline == std::string::npos) continue;
    const std::string name = parts[i].substr(0, newline);
    // Plain names only: the directory is the map, nothing outside it.
    if (name.empty() || name.find_first_of(std::string("/\0", 2)) != std::string::npos ||
        name == "." || name == "..") {
      continue;
    }
    try {
      cblox::fuzz::writeScratchFile(dir, name, std::string_view(parts[i]).substr(newline + 1));
    } catch (const std::runtime_error&) {
      // A name the file system refuses (too long): the directory just lacks that file.
    }
  }
  cblox::MapLoadReport report;
  std::string error;
  (void)cblox::loadMap(dir, &report, &error);
  return 0;
}
