// Fuzz target: readSubmapFile (core/persistence/submap_file.h). The first byte chooses what
// the rest is: even, the payload, sealed here with a valid header and checksum, and the
// manifest's expectations (size, checksum, id, layer geometry, block count) taken from it
// as a consistent manifest would list them, so that the fuzzer reaches the block section's
// decoding; odd, the whole file as is, against a fixed expectation.

#include <cstddef>
#include <cstdint>
#include <cstring>
#include <string>
#include <string_view>

#include "core/persistence/map_file_header.h"
#include "core/persistence/submap_file.h"
#include "test/fuzz/support/fuzz_files.h"

namespace {

// Little-endian value at `offset` of the payload, 0 past its end.
template <typename T>
T payloadField(std::string_view payload, size_t offset) {
  T value{};
  if (offset + sizeof(T) <= payload.size()) std::memcpy(&value, payload.data() + offset, sizeof(T));
  return value;
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  if (size == 0) return 0;
  const std::string_view rest(reinterpret_cast<const char*>(data) + 1, size - 1);
  const bool sealed = data[0] % 2 == 0;
  const std::string file =
      sealed ? cblox::sealMapFile(cblox::kSubmapFileMagic, cblox::kSubmapFileVersion, rest)
             : std::string(rest);
  cblox::SubmapId id = 0;
  cblox::LayerConfig layer;  // what loadMap passes: a validated manifest's geometry
  cblox::SubmapFileInfo expected;
  expected.file_name = cblox::submapFileName(id, 1);
  if (sealed) {
    id = payloadField<int64_t>(rest, 0);
    cblox::LayerConfig stored;
    stored.voxel_size = payloadField<float>(rest, 8);
    stored.voxels_per_side = payloadField<int32_t>(rest, 12);
    if (stored.validate().empty()) layer = stored;
    expected.file_size = file.size();
    expected.payload_xxh64 = cblox::mapFileChecksum(rest);
    expected.num_blocks = payloadField<uint64_t>(rest, 16);
  }
  const std::string& dir = cblox::fuzz::freshScratchDir();
  cblox::fuzz::writeScratchFile(dir, expected.file_name, file);
  std::string error;
  (void)cblox::readSubmapFile(dir, expected, id, layer, &error);
  return 0;
}
