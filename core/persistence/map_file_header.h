#pragma once

#include <cstddef>
#include <cstdint>
#include <optional>
#include <string>
#include <string_view>

namespace cblox {

/// The fixed 32-byte header every map file starts with (README, "Map file format"), all
/// fields little-endian:
///
///     offset  0  char[8]  magic           "CBLOXSUB" (submap file) or "CBLOXMAN" (manifest)
///     offset  8  uint32   format version  submap file 1, manifest 2; readers refuse newer ones
///     offset 12  uint32   flags           0 (reserved)
///     offset 16  uint64   payload length  bytes after the header; must equal file size - 32
///     offset 24  uint64   payload XXH64   xxHash64 (seed 0) of those bytes
///     offset 32  payload
inline constexpr size_t kMapFileHeaderBytes = 32;
/// Magic of a submap file (submap_file.h).
inline constexpr std::string_view kSubmapFileMagic = "CBLOXSUB";
/// Magic of a map manifest (map_manifest.h).
inline constexpr std::string_view kManifestFileMagic = "CBLOXMAN";

/// A verified map file: header fields and the payload.
struct MapFile {
  uint32_t version = 0;        ///< the file's format version (1 .. the reader's newest)
  uint64_t file_size = 0;      ///< bytes of the whole file
  uint64_t payload_xxh64 = 0;  ///< checksum of the payload (verified)
  std::string payload;
};

/// XXH64 with seed 0, the checksum of map files. Thread-safe (pure).
uint64_t mapFileChecksum(std::string_view bytes);

/// Header + payload: the complete bytes of a map file. Preconditions: magic has 8 characters,
/// version >= 1. Thread-safe (pure).
std::string sealMapFile(std::string_view magic, uint32_t version, std::string_view payload);

/// Reads the map file at `path` and checks, in this order, that it holds a whole header, the
/// magic, that the version is in [1, newest_version], the flags are 0, that the payload length
/// equals the bytes that follow (checked before allocating, so a header claiming 2^40 bytes
/// costs nothing), and the payload's XXH64. Returns std::nullopt with "<path>: <what is
/// wrong>" in *error (if non-null) otherwise: "cannot open", "truncated", "bad magic",
/// "format version V is newer than this reader supports (N)", "payload length ... out of
/// bounds", "checksum mismatch", read errors with their errno text. `what` names the kind of
/// file in messages ("submap file", "map manifest"). Thread-safe (no shared state).
std::optional<MapFile> readMapFile(const std::string& path, std::string_view magic,
                                   uint32_t newest_version, std::string_view what,
                                   std::string* error);

}  // namespace cblox
