#pragma once

#include <cstdint>
#include <optional>
#include <string>
#include <string_view>

#include "core/submap/submap.h"
#include "core/tsdf/layer_config.h"
#include "core/tsdf/tsdf_layer.h"

namespace cblox {

/// Newest submap file format version this build writes and reads.
inline constexpr uint32_t kSubmapFileVersion = 1;
/// zstd level of the block section: fast, and TSDF blocks compress about as well at 3 as at 9.
inline constexpr int kSubmapFileZstdLevel = 3;

/// One written submap file, as the manifest lists it (map_manifest.h).
struct SubmapFileInfo {
  std::string file_name;       ///< submapFileName(id, generation), relative to the map directory
  uint64_t file_size = 0;      ///< bytes of the whole file, header included
  uint64_t payload_xxh64 = 0;  ///< XXH64 of the payload, as in the file's header
  uint64_t num_blocks = 0;     ///< blocks stored

  friend bool operator==(const SubmapFileInfo&, const SubmapFileInfo&) = default;
};

/// "submap_<id>_g<generation>.cbsub": the voxels of submap `id` as written by checkpoint
/// `generation`. A checkpoint never overwrites a file that the committed manifest lists, so
/// a crash before the new manifest is renamed into place leaves the old map loadable.
/// Thread-safe (pure).
std::string submapFileName(SubmapId id, uint64_t generation);

/// Parses a submapFileName() (decimal, no sign, no leading zeros but "0"); false for any other
/// name (temporary files, paths with '/', ...). Outputs may be null. Thread-safe (pure).
bool parseSubmapFileName(std::string_view name, SubmapId* id, uint64_t* generation);

/// The complete bytes of the submap file of `layer` (submap `id`): header (map_file_header.h)
/// and a payload of
///
///     int64  submap id
///     f32    voxel size (m)            int32 voxels per side (N^3 voxels per block)
///     uint64 block count               uint8 codec (1 = zstd)
///     uint64 uncompressed size         uint64 compressed size
///     bytes  the block section, one zstd frame (with its content size)
///
/// where the uncompressed block section holds, for each block in ascending packGridIndex()
/// order, int32 x y z (block index) followed by N^3 f32 distances, N^3 f32 weights, N^3 red,
/// N^3 green, N^3 blue bytes (planar, so that zstd finds the repetition; voxels in
/// Block::linearIndex order). The voxels' padding byte is not stored (it is always 0).
/// Deterministic: the same layer gives the same bytes. The caller guarantees that nothing
/// modifies the layer meanwhile (writeSubmapFile takes care of that). Throws std::runtime_error
/// only if zstd fails (out of memory).
std::string encodeSubmapFile(SubmapId id, const TsdfLayer& layer);

/// Writes the voxels of `submap` to <dir>/submapFileName(submap.id(), generation) atomically
/// (writeFileAtomically) and returns what the manifest lists for it; std::nullopt with a
/// message naming the path in *error (if non-null) when it cannot be written. Metadata (pose,
/// keyframes, ...) is not in this file but in the manifest. The layer is read under
/// Submap::lockLayer() (integration of an active submap waits for the copy of its voxels, not
/// for compression or I/O). Thread-safety: any thread for an ACTIVE submap; for a FINISHED
/// submap only the thread that owns finished layers (the fusion worker), or any thread while
/// nothing modifies finished layers (see submap.h).
std::optional<SubmapFileInfo> writeSubmapFile(const Submap& submap, const std::string& dir,
                                              uint64_t generation, std::string* error);

/// Reads <dir>/expected.file_name into a new layer and verifies everything: the header
/// (readMapFile: magic, version, length, checksum), that size and checksum are the ones the
/// manifest lists (`expected`), that the stored submap id and layer geometry equal
/// `expected_id` and `expected_config`, every length against the bytes that remain and the
/// zstd frame's content size against the declared sizes before anything is allocated (blocks
/// are allocated only as their bytes are decompressed), block indices in the packable range
/// and not repeated. Returns std::nullopt with "<path>: <what is wrong>" in *error (if
/// non-null) otherwise, e.g. "cannot open submap file: No such file or directory" for a file
/// the manifest lists but that is missing. Thread-safe (no shared state).
std::optional<TsdfLayer> readSubmapFile(const std::string& dir, const SubmapFileInfo& expected,
                                        SubmapId expected_id, const LayerConfig& expected_config,
                                        std::string* error);

}  // namespace cblox
