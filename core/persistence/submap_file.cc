#include "core/persistence/submap_file.h"

#include <algorithm>
#include <charconv>
#include <filesystem>
#include <limits>
#include <memory>
#include <mutex>
#include <stdexcept>
#include <utility>
#include <vector>

#include <zstd.h>

#include "core/io/atomic_file.h"
#include "core/persistence/byte_codec.h"
#include "core/persistence/map_file_header.h"

namespace cblox {
namespace {

using persistence_detail::ByteReader;
using persistence_detail::ByteWriter;

constexpr uint8_t kCodecZstd = 1;
// zstd cannot expand more than this: a block of at most 128 KiB of content takes at least
// 4 bytes (an RLE block). A declared size above it is a lie, refused before decoding.
constexpr uint64_t kMaxZstdRatio = 32768;

uint64_t blockRecordBytes(int voxels_per_side) {
  const auto n = static_cast<uint64_t>(voxels_per_side) * voxels_per_side * voxels_per_side;
  return 12 + n * 11;  // index, distances, weights, red, green, blue
}

// The uncompressed block section (see encodeSubmapFile), blocks in packed-key order.
std::string encodeBlockSection(const TsdfLayer& layer) {
  std::vector<uint64_t> keys;
  keys.reserve(layer.numBlocks());
  for (const auto& [key, block] : layer.blocks()) keys.push_back(key);
  std::sort(keys.begin(), keys.end());
  std::string out;
  out.reserve(keys.size() * blockRecordBytes(layer.voxelsPerSide()));
  ByteWriter w(&out);
  for (const uint64_t key : keys) {
    const Block& block = *layer.blocks().at(key);
    const TsdfVoxel* voxels = block.voxels();
    const int n = block.numVoxels();
    w.i32(block.index().x());
    w.i32(block.index().y());
    w.i32(block.index().z());
    for (int i = 0; i < n; ++i) w.f32(voxels[i].distance);
    for (int i = 0; i < n; ++i) w.f32(voxels[i].weight);
    for (int i = 0; i < n; ++i) w.u8(voxels[i].color.r);
    for (int i = 0; i < n; ++i) w.u8(voxels[i].color.g);
    for (int i = 0; i < n; ++i) w.u8(voxels[i].color.b);
  }
  return out;
}

// Compresses the section and seals the whole file.
std::string sealSubmapFile(SubmapId id, const LayerConfig& config, uint64_t num_blocks,
                           const std::string& section) {
  std::string compressed(ZSTD_compressBound(section.size()), '\0');
  const size_t size = ZSTD_compress(compressed.data(), compressed.size(), section.data(),
                                    section.size(), kSubmapFileZstdLevel);
  if (ZSTD_isError(size)) {
    throw std::runtime_error(std::string("zstd compression failed: ") + ZSTD_getErrorName(size));
  }
  compressed.resize(size);
  std::string payload;
  payload.reserve(64 + compressed.size());
  ByteWriter w(&payload);
  w.i64(id);
  w.f32(config.voxel_size);
  w.i32(config.voxels_per_side);
  w.u64(num_blocks);
  w.u8(kCodecZstd);
  w.u64(section.size());
  w.u64(compressed.size());
  w.bytes(compressed);
  return sealMapFile(kSubmapFileMagic, kSubmapFileVersion, payload);
}

struct DctxDeleter {
  void operator()(ZSTD_DCtx* dctx) const { ZSTD_freeDCtx(dctx); }
};

// Decompresses the block section block by block into *layer. Empty string when fine, else
// what is wrong.
std::string decodeBlockSection(std::string_view compressed, uint64_t num_blocks, TsdfLayer* layer) {
  const std::unique_ptr<ZSTD_DCtx, DctxDeleter> dctx(ZSTD_createDCtx());
  if (!dctx) return "zstd: cannot create a decompression context";
  const int n = layer->voxelsPerSide() * layer->voxelsPerSide() * layer->voxelsPerSide();
  std::string record(blockRecordBytes(layer->voxelsPerSide()), '\0');
  ZSTD_inBuffer in{compressed.data(), compressed.size(), 0};
  size_t hint = 1;  // ZSTD_decompressStream's last return: 0 once the frame is complete
  // Fills `out` completely; otherwise returns what is wrong.
  const auto fill = [&](ZSTD_outBuffer* out) -> std::string {
    while (out->pos < out->size) {
      const size_t in_before = in.pos, out_before = out->pos;
      hint = ZSTD_decompressStream(dctx.get(), out, &in);
      if (ZSTD_isError(hint)) {
        return std::string("decompression error in the block section: ") + ZSTD_getErrorName(hint);
      }
      if (out->pos < out->size && (hint == 0 || (in.pos == in_before && out->pos == out_before))) {
        return "decompression error in the block section: the zstd frame ends before the " +
               std::to_string(num_blocks) + " declared blocks";
      }
    }
    return "";
  };
  for (uint64_t b = 0; b < num_blocks; ++b) {
    ZSTD_outBuffer out{record.data(), record.size(), 0};
    if (std::string e = fill(&out); !e.empty()) return e;
    ByteReader r(record);
    BlockIndex index = BlockIndex::Zero();
    r.i32(&index.x());
    r.i32(&index.y());
    r.i32(&index.z());
    if (!gridIndexInRange(index)) {
      return "block " + std::to_string(b) + " has an index outside the packable range";
    }
    bool fresh = false;
    Block* block = layer->allocateBlock(index, &fresh);
    if (!fresh) return "block " + std::to_string(b) + " repeats an index";
    TsdfVoxel* voxels = block->voxels();
    for (int i = 0; i < n; ++i) r.f32(&voxels[i].distance);
    for (int i = 0; i < n; ++i) r.f32(&voxels[i].weight);
    for (int i = 0; i < n; ++i) r.u8(&voxels[i].color.r);
    for (int i = 0; i < n; ++i) r.u8(&voxels[i].color.g);
    for (int i = 0; i < n; ++i) r.u8(&voxels[i].color.b);
  }
  // The frame must end here: no further content, no bytes after it.
  while (hint != 0) {
    char extra = 0;
    ZSTD_outBuffer out{&extra, 1, 0};
    const size_t in_before = in.pos;
    hint = ZSTD_decompressStream(dctx.get(), &out, &in);
    if (ZSTD_isError(hint)) {
      return std::string("decompression error in the block section: ") + ZSTD_getErrorName(hint);
    }
    if (out.pos > 0) return "the block section holds more than the declared blocks";
    if (hint != 0 && in.pos == in_before) {
      return "decompression error in the block section: the zstd frame is truncated";
    }
  }
  if (in.pos != in.size) return "bytes after the zstd frame of the block section";
  return "";
}

std::optional<TsdfLayer> fail(std::string* error, const std::string& path,
                              const std::string& what) {
  if (error != nullptr) *error = path + ": " + what;
  return std::nullopt;
}

}  // namespace

std::string submapFileName(SubmapId id, uint64_t generation) {
  return "submap_" + std::to_string(id) + "_g" + std::to_string(generation) + ".cbsub";
}

bool parseSubmapFileName(std::string_view name, SubmapId* id, uint64_t* generation) {
  constexpr std::string_view kPrefix = "submap_", kSuffix = ".cbsub";
  if (!name.starts_with(kPrefix) || !name.ends_with(kSuffix)) return false;
  name.remove_prefix(kPrefix.size());
  name.remove_suffix(kSuffix.size());
  const size_t sep = name.find("_g");
  if (sep == std::string_view::npos) return false;
  const auto number = [](std::string_view digits, auto* value) {
    if (digits.empty() || (digits.size() > 1 && digits[0] == '0')) return false;
    if (digits.find_first_not_of("0123456789") != std::string_view::npos) return false;
    const auto r = std::from_chars(digits.data(), digits.data() + digits.size(), *value);
    return r.ec == std::errc() && r.ptr == digits.data() + digits.size();
  };
  SubmapId parsed_id = 0;
  uint64_t parsed_generation = 0;
  if (!number(name.substr(0, sep), &parsed_id) ||
      !number(name.substr(sep + 2), &parsed_generation)) {
    return false;
  }
  if (id != nullptr) *id = parsed_id;
  if (generation != nullptr) *generation = parsed_generation;
  return true;
}

std::string encodeSubmapFile(SubmapId id, const TsdfLayer& layer) {
  return sealSubmapFile(id, layer.config(), layer.numBlocks(), encodeBlockSection(layer));
}

std::optional<SubmapFileInfo> writeSubmapFile(const Submap& submap, const std::string& dir,
                                              uint64_t generation, std::string* error) {
  std::string section;
  uint64_t num_blocks = 0;
  {
    // Harmless for finished submaps (finish() only holds it briefly); needed for the active one.
    const std::unique_lock lock = submap.lockLayer();
    section = encodeBlockSection(submap.layer());
    num_blocks = submap.layer().numBlocks();
  }
  SubmapFileInfo info;
  info.file_name = submapFileName(submap.id(), generation);
  const std::string path = (std::filesystem::path(dir) / info.file_name).string();
  std::string bytes;
  try {
    bytes = sealSubmapFile(submap.id(), submap.layerConfig(), num_blocks, section);
  } catch (const std::exception& e) {
    if (error != nullptr) *error = path + ": " + e.what();
    return std::nullopt;
  }
  section = std::string();  // free it before the write
  if (!writeFileAtomically(path, bytes, error)) return std::nullopt;
  info.file_size = bytes.size();
  info.payload_xxh64 = mapFileChecksum(std::string_view(bytes).substr(kMapFileHeaderBytes));
  info.num_blocks = num_blocks;
  return info;
}

std::optional<TsdfLayer> readSubmapFile(const std::string& dir, const SubmapFileInfo& expected,
                                        SubmapId expected_id, const LayerConfig& expected_config,
                                        std::string* error) {
  const std::string path = (std::filesystem::path(dir) / expected.file_name).string();
  std::optional<MapFile> file =
      readMapFile(path, kSubmapFileMagic, kSubmapFileVersion, "submap file", error);
  if (!file) return std::nullopt;
  if (file->file_size != expected.file_size || file->payload_xxh64 != expected.payload_xxh64) {
    return fail(error, path,
                "checksum mismatch with the manifest: the file is not the one the manifest lists "
                "(size " +
                    std::to_string(file->file_size) + ", manifest says " +
                    std::to_string(expected.file_size) + ")");
  }
  ByteReader r(file->payload);
  int64_t id = 0;
  LayerConfig config;
  uint64_t num_blocks = 0, uncompressed = 0, compressed_size = 0;
  uint8_t codec = 0;
  r.i64(&id);
  r.f32(&config.voxel_size);
  r.i32(&config.voxels_per_side);
  r.u64(&num_blocks);
  r.u8(&codec);
  r.u64(&uncompressed);
  r.u64(&compressed_size);
  if (!r.ok()) return fail(error, path, "truncated: the payload ends inside the submap header");
  if (id != expected_id) {
    return fail(error, path,
                "holds submap " + std::to_string(id) + ", the manifest lists it as " +
                    std::to_string(expected_id));
  }
  if (const std::string invalid = config.validate(); !invalid.empty()) {
    return fail(error, path, "invalid layer geometry: " + invalid);
  }
  if (config.voxel_size != expected_config.voxel_size ||
      config.voxels_per_side != expected_config.voxels_per_side) {
    return fail(error, path,
                "layer geometry (voxel size " + std::to_string(config.voxel_size) + ", " +
                    std::to_string(config.voxels_per_side) +
                    " voxels per side) differs from the manifest's");
  }
  if (num_blocks != expected.num_blocks) {
    return fail(error, path,
                "holds " + std::to_string(num_blocks) + " blocks, the manifest says " +
                    std::to_string(expected.num_blocks));
  }
  if (codec != kCodecZstd) {
    return fail(error, path, "unknown block codec " + std::to_string(codec));
  }
  if (compressed_size != r.remaining()) {
    return fail(error, path,
                "compressed size " + std::to_string(compressed_size) + " out of bounds: " +
                    std::to_string(r.remaining()) + " bytes remain in the payload");
  }
  const uint64_t record = blockRecordBytes(config.voxels_per_side);
  if (num_blocks > std::numeric_limits<uint64_t>::max() / record ||
      uncompressed != num_blocks * record) {
    return fail(error, path,
                "uncompressed size " + std::to_string(uncompressed) + " does not match " +
                    std::to_string(num_blocks) + " blocks of " + std::to_string(record) + " bytes");
  }
  if (uncompressed / kMaxZstdRatio > compressed_size) {
    return fail(error, path,
                "uncompressed size " + std::to_string(uncompressed) + " out of bounds for " +
                    std::to_string(compressed_size) + " compressed bytes");
  }
  std::string_view compressed;
  r.bytes(compressed_size, &compressed);
  const unsigned long long content = ZSTD_getFrameContentSize(compressed.data(), compressed.size());
  if (content == ZSTD_CONTENTSIZE_ERROR || content == ZSTD_CONTENTSIZE_UNKNOWN) {
    return fail(error, path,
                "decompression error: the block section is not a zstd frame with "
                "a content size");
  }
  if (content != uncompressed) {
    return fail(error, path,
                "zstd frame content size " + std::to_string(content) +
                    " differs from the declared " + std::to_string(uncompressed));
  }
  TsdfLayer layer(config);
  if (const std::string e = decodeBlockSection(compressed, num_blocks, &layer); !e.empty()) {
    return fail(error, path, e);
  }
  return layer;
}

}  // namespace cblox
