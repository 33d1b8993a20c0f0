// Fuzz target: the tracker's map files (core/persistence/sparse_map_file.h, id_lease.h) and
// what a resumed tracker does with them (daemon/tracker/tracker_resume.h, then
// SparseMap::restore). The first byte chooses what the rest is:
//   0  an index payload as is (decodeTrackerMapIndex: the zstd section's bounds)
//   1  the raw index section, compressed here, so the fuzzer reaches the parsing behind zstd
//   2  a keyframe chunk payload as is (decodeKeyframeChunk)
//   3  the raw chunk section, compressed here
//   4+ a checkpoint directory: three parts (fuzz_files.h separator), the index section, the
//      chunk section and the lease payload, each compressed and sealed with a valid header,
//      written as tracker_map.cbtm, keyframes_e0_g1.cbkf and keyframe_ids.lease; an index
//      that decodes is pointed at that one chunk file with its true size and checksum (which
//      the fuzzer cannot forge), so the load goes on to the features, the consistency checks
//      and, for a map loadTrackerResume accepts, SparseMap::restore (8 pyramid levels).

#include <cstddef>
#include <cstdint>
#include <optional>
#include <stdexcept>
#include <string>
#include <string_view>

#include "core/persistence/id_lease.h"
#include "core/persistence/map_file_header.h"
#include "core/persistence/sparse_map_file.h"
#include "core/persistence/zstd_blob.h"
#include "core/tracking/sparse_map.h"
#include "daemon/tracker/tracker_resume.h"
#include "test/fuzz/support/fuzz_files.h"

namespace {

std::string compressed(std::string_view raw) {
  std::string out;
  cblox::appendZstdBlob(raw, 1, &out);
  return out;
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  using namespace cblox;
  if (size == 0) return 0;
  const std::string_view rest(reinterpret_cast<const char*>(data) + 1, size - 1);
  std::string error;
  switch (data[0]) {
    case 0:
      (void)decodeTrackerMapIndex(rest, &error);
      return 0;
    case 1:
      (void)decodeTrackerMapIndex(compressed(rest), &error);
      return 0;
    case 2:
      (void)decodeKeyframeChunk(rest, &error);
      return 0;
    case 3:
      (void)decodeKeyframeChunk(compressed(rest), &error);
      return 0;
    default:
      break;
  }
  const auto parts = fuzz::splitParts(data + 1, size - 1, 3);
  const std::string& dir = fuzz::freshScratchDir();
  const std::string chunk_payload = compressed(parts[1]);
  const std::string chunk = sealMapFile(kKeyframeChunkMagic, kTrackerMapVersion, chunk_payload);
  std::string index_payload = compressed(parts[0]);
  if (std::optional<TrackerMapIndex> index = decodeTrackerMapIndex(index_payload, &error)) {
    index->chunks = {{keyframeChunkFileName(0, 1), chunk.size(), mapFileChecksum(chunk_payload)}};
    for (uint32_t& c : index->keyframe_chunk) c = c == kNoKeyframeChunk ? c : 0;
    index_payload = encodeTrackerMapIndex(*index);
  }
  fuzz::writeScratchFile(dir, kTrackerMapFileName,
                         sealMapFile(kTrackerMapMagic, kTrackerMapVersion, index_payload));
  fuzz::writeScratchFile(dir, keyframeChunkFileName(0, 1), chunk);
  fuzz::writeScratchFile(dir, kIdLeaseFileName, sealMapFile("CBLOXLSE", 1, parts[2]));
  const std::optional<TrackerResume> resume = loadTrackerResume(dir, &error);
  if (!resume || !resume->map) return 0;
  SparseMap map;
  try {
    map.restore(resume->map->map, 8, resume->keyframe_floor, resume->landmark_floor);
  } catch (const std::invalid_argument&) {
    // refused: an inconsistent map (e.g. an octave outside the pyramid)
  }
  return 0;
}
