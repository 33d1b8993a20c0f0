// Fuzz target: readManifest (core/persistence/map_manifest.h). The first byte chooses what
// the rest is: even, the payload, sealed here with a valid header and checksum so that the
// fuzzer reaches the manifest's parsing behind the checksum; odd, the whole file as is
// (header checks).

#include <cstddef>
#include <cstdint>
#include <string>
#include <string_view>

#include "core/persistence/map_file_header.h"
#include "core/persistence/map_manifest.h"
#include "test/fuzz/support/fuzz_files.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  if (size == 0) return 0;
  const std::string_view rest(reinterpret_cast<const char*>(data) + 1, size - 1);
  const std::string& dir = cblox::fuzz::freshScratchDir();
  cblox::fuzz::writeScratchFile(dir, "manifest.cbmap",
                                data[0] % 2 == 0 ? cblox::sealMapFile(cblox::kManifestFileMagic,
                                                                      cblox::kManifestVersion, rest)
                                                 : std::string(rest));
  std::string error;
  (void)cblox::readManifest(dir, &error);
  return 0;
}
