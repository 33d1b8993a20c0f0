// Format-level tests: the file header, submap files and the manifest, including hostile input.

#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <random>
#include <string>
#include <vector>

#include <gtest/gtest.h>
#include <zstd.h>

#include "core/io/atomic_file.h"
#include "core/persistence/byte_codec.h"
#include "core/persistence/map_file_header.h"
#include "core/persistence/map_manifest.h"
#include "core/persistence/submap_file.h"
#include "test/persistence/map_test_collection.h"
#include "test/test_support/temp_dir.h"

namespace cblox {
namespace {

using persistence_detail::ByteWriter;

// Expects `error` to contain every fragment.
void expectError(const std::string& error, std::initializer_list<std::string> fragments) {
  for (const std::string& f : fragments) {
    EXPECT_NE(error.find(f), std::string::npos) << "'" << f << "' not in: " << error;
  }
  std::printf("  rejected: %s\n", error.c_str());
}

// Overwrites bytes at `offset` of the file.
void patchFile(const std::string& path, size_t offset, const std::string& bytes) {
  std::string content = test::readFile(path);
  ASSERT_LE(offset + bytes.size(), content.size());
  content.replace(offset, bytes.size(), bytes);
  ASSERT_TRUE(writeFileAtomically(path, content, nullptr));
}

std::string le32(uint32_t v) {
  std::string s;
  ByteWriter(&s).u32(v);
  return s;
}
std::string le64(uint64_t v) {
  std::string s;
  ByteWriter(&s).u64(v);
  return s;
}

class MapFileFormat : public ::testing::Test {
 protected:
  test::TempDir dir_{"cblox_mapfile"};
};

TEST_F(MapFileFormat, HeaderLayoutIsLittleEndianAndChecksummed) {
  const std::string bytes = sealMapFile(kManifestFileMagic, 1, "payload");
  ASSERT_EQ(bytes.size(), kMapFileHeaderBytes + 7);
  EXPECT_EQ(bytes.substr(0, 8), "CBLOXMAN");
  EXPECT_EQ(bytes.substr(8, 4), le32(1));
  EXPECT_EQ(bytes.substr(12, 4), le32(0));
  EXPECT_EQ(bytes.substr(16, 8), le64(7));
  EXPECT_EQ(bytes.substr(24, 8), le64(mapFileChecksum("payload")));
  EXPECT_EQ(mapFileChecksum(""), 0xef46db3751d8e999ull);  // the XXH64 reference value
  const std::string p = dir_.write("f", bytes);
  std::string error;
  const auto file = readMapFile(p, kManifestFileMagic, 1, "map manifest", &error);
  ASSERT_TRUE(file) << error;
  EXPECT_EQ(file->payload, "payload");
  EXPECT_EQ(file->version, 1u);
  EXPECT_EQ(file->file_size, bytes.size());
}

TEST_F(MapFileFormat, HeaderErrorsNameTheFileAndTheProblem) {
  std::string error;
  const auto read = [&](const std::string& p, uint32_t newest = 1) {
    return readMapFile(p, kSubmapFileMagic, newest, "submap file", &error).has_value();
  };
  const std::string good = sealMapFile(kSubmapFileMagic, 1, std::string(100, 'x'));

  EXPECT_FALSE(read(dir_.file("absent")));
  expectError(error, {dir_.file("absent"), "cannot open submap file", "No such file"});

  const std::string magic = dir_.write("magic", "CBLOXMAN" + good.substr(8));
  EXPECT_FALSE(read(magic));
  expectError(error, {magic, "bad magic \"CBLOXMAN\"", "expected \"CBLOXSUB\""});

  const std::string newer = dir_.write("newer", good);
  patchFile(newer, 8, le32(999));
  EXPECT_FALSE(read(newer));
  expectError(error, {newer, "version 999 is newer than this reader supports (1)"});
  EXPECT_TRUE(read(newer, 999));  // a reader that knows 999

  const std::string short_header = dir_.write("short", good.substr(0, 20));
  EXPECT_FALSE(read(short_header));
  expectError(error, {short_header, "truncated", "20 bytes"});

  const std::string truncated = dir_.write("truncated", good.substr(0, good.size() - 1));
  EXPECT_FALSE(read(truncated));
  expectError(error, {truncated, "truncated: payload length 100 out of bounds", "99 bytes"});

  const std::string longer = dir_.write("longer", good + "!");
  EXPECT_FALSE(read(longer));
  expectError(error, {longer, "payload length 100 out of bounds", "101 bytes"});

  // A header claiming 2^40 payload bytes is refused from the file size, before allocating.
  const std::string hostile = dir_.write("hostile", good);
  patchFile(hostile, 16, le64(uint64_t{1} << 40));
  EXPECT_FALSE(read(hostile));
  expectError(error, {hostile, "payload length 1099511627776 out of bounds"});

  const std::string flipped = dir_.write("flipped", good);
  patchFile(flipped, kMapFileHeaderBytes + 50, "y");
  EXPECT_FALSE(read(flipped));
  expectError(error, {flipped, "checksum mismatch"});

  const std::string flags = dir_.write("flags", good);
  patchFile(flags, 12, le32(4));
  EXPECT_FALSE(read(flags));
  expectError(error, {flags, "flags"});

  const std::string zero = dir_.write("zero", good);
  patchFile(zero, 8, le32(0));
  EXPECT_FALSE(read(zero));
  expectError(error, {zero, "version 0"});
}

TEST_F(MapFileFormat, SubmapFileNames) {
  EXPECT_EQ(submapFileName(12, 3), "submap_12_g3.cbsub");
  SubmapId id = -1;
  uint64_t generation = 0;
  EXPECT_TRUE(parseSubmapFileName("submap_12_g3.cbsub", &id, &generation));
  EXPECT_EQ(id, 12);
  EXPECT_EQ(generation, 3u);
  EXPECT_TRUE(parseSubmapFileName("submap_0_g0.cbsub", nullptr, nullptr));
  for (const char* bad :
       {"submap_12_g3.cbsub.tmp.5.0", "submap_-1_g3.cbsub", "submap_01_g3.cbsub",
        "submap_1_g.cbsub", "submap__g1.cbsub", "../submap_1_g1.cbsub", "submap_1_g1.cbsu",
        "submap_1.cbsub", "submap_99999999999999999999_g1.cbsub", "manifest.cbmap"}) {
    EXPECT_FALSE(parseSubmapFileName(bad, nullptr, nullptr)) << bad;
  }
}

// Every voxel of integrated and awkward content comes back bit-identical; the output is
// deterministic and compressed.
TEST_F(MapFileFormat, SubmapFileRoundTripIsBitExact) {
  const auto collection = test::buildTestCollection();
  for (const auto& submap : collection->submaps()) {
    SCOPED_TRACE("submap " + std::to_string(submap->id()));
    std::string error;
    const auto info = writeSubmapFile(*submap, dir_.path().string(), 7, &error);
    ASSERT_TRUE(info) << error;
    EXPECT_EQ(info->file_name, submapFileName(submap->id(), 7));
    EXPECT_EQ(info->num_blocks, submap->numBlocks());
    const std::string bytes = test::readFile(dir_.file(info->file_name));
    EXPECT_EQ(bytes.size(), info->file_size);
    EXPECT_EQ(bytes, encodeSubmapFile(submap->id(), submap->layer()));  // deterministic
    const size_t raw = submap->numBlocks() * (12 + 512 * 11);
    if (submap->numBlocks() > 10) {
      EXPECT_LT(bytes.size(), raw / 2) << "raw " << raw;
    }
    std::printf("  submap %lld: %zu blocks, %zu bytes raw, %zu bytes in the file\n",
                static_cast<long long>(submap->id()), submap->numBlocks(), raw, bytes.size());
    const auto layer = readSubmapFile(dir_.path().string(), *info, submap->id(),
                                      collection->config().layer, &error);
    ASSERT_TRUE(layer) << error;
    EXPECT_TRUE(test::sameVoxels(test::layerVoxels(submap->layer()), test::layerVoxels(*layer)));
  }
}

// A submap file whose payload is forged (with a valid checksum, as a hostile writer would)
// is refused with a clear message, never crashes and never allocates the claimed sizes.
class SubmapFileForged : public MapFileFormat {
 protected:
  struct Fields {
    int64_t id = 4;
    float voxel_size = test::kVoxelSize;
    int32_t voxels_per_side = 8;
    uint64_t num_blocks = 1;
    uint8_t codec = 1;
    int64_t uncompressed_delta = 0;  // added to the true uncompressed size
    std::string compressed;          // the true zstd frame when empty
    std::string frame_suffix;        // appended to the frame (counted in its size)
    std::string tail;                // bytes after the compressed section
  };

  // One block of the given index, encoded as the writer would, then forged by `f`.
  std::string forge(const Fields& f, const BlockIndex& index = BlockIndex(1, 2, 3)) {
    TsdfLayer layer(test::mapTestConfig().layer);
    layer.allocateBlock(index)->voxel(3).weight = 2.0f;
    const std::string real = encodeSubmapFile(4, layer);
    // The real payload: id(8) size(4) vps(4) blocks(8) codec(1) raw(8) compressed(8) frame.
    const std::string frame = real.substr(kMapFileHeaderBytes + 41);
    std::string payload;
    ByteWriter w(&payload);
    w.i64(f.id);
    w.f32(f.voxel_size);
    w.i32(f.voxels_per_side);
    w.u64(f.num_blocks);
    w.u8(f.codec);
    const std::string compressed = (f.compressed.empty() ? frame : f.compressed) + f.frame_suffix;
    w.u64(static_cast<uint64_t>(static_cast<int64_t>(12 + 512 * 11) + f.uncompressed_delta));
    w.u64(compressed.size());
    w.bytes(compressed);
    w.bytes(f.tail);
    return sealMapFile(kSubmapFileMagic, kSubmapFileVersion, payload);
  }

  // Writes `bytes` as submap 4's file and reads it with a matching manifest entry.
  bool read(const std::string& bytes, std::string* error, uint64_t listed_blocks = 1) {
    const std::string name = submapFileName(4, 1);
    dir_.write(name, bytes);
    SubmapFileInfo info{name, bytes.size(),
                        mapFileChecksum(std::string_view(bytes).substr(kMapFileHeaderBytes)),
                        listed_blocks};
    return readSubmapFile(dir_.path().string(), info, 4, test::mapTestConfig().layer, error)
        .has_value();
  }
  std::string path() const { return dir_.file(submapFileName(4, 1)); }
};

TEST_F(SubmapFileForged, IsRefusedWithAClearMessage) {
  std::string error;
  ASSERT_TRUE(read(forge({}), &error)) << error;

  Fields f;
  f.id = 5;
  EXPECT_FALSE(read(forge(f), &error));
  expectError(error, {path(), "holds submap 5, the manifest lists it as 4"});

  f = Fields{};
  f.voxels_per_side = 16;
  EXPECT_FALSE(read(forge(f), &error));
  expectError(error, {path(), "differs from the manifest"});
  f.voxels_per_side = 6;
  EXPECT_FALSE(read(forge(f), &error));
  expectError(error, {path(), "voxels_per_side"});

  f = Fields{};
  f.codec = 2;
  EXPECT_FALSE(read(forge(f), &error));
  expectError(error, {path(), "unknown block codec 2"});

  // 2^40 blocks claimed: the sizes do not match, nothing is allocated.
  f = Fields{};
  f.num_blocks = uint64_t{1} << 40;
  EXPECT_FALSE(read(forge(f), &error, f.num_blocks));
  expectError(error, {path(), "does not match 1099511627776 blocks"});
  f.num_blocks = ~uint64_t{0};
  EXPECT_FALSE(read(forge(f), &error, f.num_blocks));
  expectError(error, {path(), "does not match"});

  // Consistent sizes, but far more than a zstd frame of that length can hold.
  f = Fields{};
  f.num_blocks = 1000000;
  f.uncompressed_delta = static_cast<int64_t>(999999) * (12 + 512 * 11);
  EXPECT_FALSE(read(forge(f), &error, f.num_blocks));
  expectError(error, {path(), "out of bounds for"});

  // Plausible sizes the frame does not have: its content size disagrees.
  f.num_blocks = 2;
  f.uncompressed_delta = 12 + 512 * 11;
  EXPECT_FALSE(read(forge(f), &error, 2));
  expectError(error, {path(), "zstd frame content size 5644 differs from the declared 11288"});

  f = Fields{};
  f.compressed = "not a zstd frame at all";
  EXPECT_FALSE(read(forge(f), &error));
  expectError(error, {path(), "decompression error"});

  f = Fields{};
  f.frame_suffix = "xyz";
  EXPECT_FALSE(read(forge(f), &error));
  expectError(error, {path(), "bytes after the zstd frame"});

  f = Fields{};
  f.tail = "xyz";
  EXPECT_FALSE(read(forge(f), &error));
  expectError(error, {path(), "out of bounds: ", "bytes remain in the payload"});

  // The payload ends inside the submap header.
  std::string payload;
  ByteWriter(&payload).i64(4);
  EXPECT_FALSE(read(sealMapFile(kSubmapFileMagic, 1, payload), &error));
  expectError(error, {path(), "truncated"});
}

TEST_F(SubmapFileForged, RepeatedBlockAndTruncatedFrameAreRefused) {
  // A block section of empty blocks with these indices, compressed as the writer does.
  const auto frameOf = [](const std::vector<BlockIndex>& indices) {
    std::string section;
    ByteWriter w(&section);
    for (const BlockIndex& index : indices) {
      w.i32(index.x());
      w.i32(index.y());
      w.i32(index.z());
      w.bytes(std::string(512 * 11, '\0'));
    }
    std::string frame(ZSTD_compressBound(section.size()), '\0');
    frame.resize(ZSTD_compress(frame.data(), frame.size(), section.data(), section.size(), 3));
    return frame;
  };
  Fields f;
  f.num_blocks = 2;
  f.uncompressed_delta = 12 + 512 * 11;
  f.compressed = frameOf({BlockIndex(1, 2, 3), BlockIndex(1, 2, 3)});
  std::string error;
  EXPECT_FALSE(read(forge(f), &error, 2));
  expectError(error, {path(), "block 1 repeats an index"});
  const std::string frame = f.compressed;

  f = Fields{};
  f.compressed = frameOf({BlockIndex(0, kGridIndexMax + 1, 0)});
  EXPECT_FALSE(read(forge(f), &error));
  expectError(error, {path(), "block 0 has an index outside the packable range"});
  f = Fields{};
  f.num_blocks = 2;
  f.uncompressed_delta = 12 + 512 * 11;

  // A frame cut short (its content size still says two blocks).
  f.compressed = frame.substr(0, frame.size() - 4);
  EXPECT_FALSE(read(forge(f), &error, 2));
  expectError(error, {path(), "decompression error"});
}

// Random corruption of a real payload (resealed so that the checksum passes): every outcome
// is a clean error or a valid layer, never a crash.
TEST_F(SubmapFileForged, RandomCorruptionNeverCrashes) {
  const auto collection = test::buildTestCollection();
  const std::string real = encodeSubmapFile(1, collection->getSubmap(1)->layer());
  const std::string payload = real.substr(kMapFileHeaderBytes);
  std::mt19937 rng(15);
  int refused = 0;
  for (int trial = 0; trial < 300; ++trial) {
    std::string forged = payload;
    const int flips = 1 + static_cast<int>(rng() % 4);
    for (int i = 0; i < flips; ++i) {
      forged[rng() % forged.size()] = static_cast<char>(rng());
    }
    if (trial % 3 == 0) forged.resize(rng() % forged.size());
    const std::string bytes = sealMapFile(kSubmapFileMagic, 1, forged);
    const std::string name = submapFileName(1, 1);
    dir_.write(name, bytes);
    SubmapFileInfo info{name, bytes.size(), mapFileChecksum(forged),
                        collection->getSubmap(1)->numBlocks()};
    std::string error;
    if (!readSubmapFile(dir_.path().string(), info, 1, test::mapTestConfig().layer, &error)) {
      ++refused;
      EXPECT_NE(error.find(dir_.file(name)), std::string::npos) << error;
    }
  }
  // Flipped voxel bytes inside zstd literals decode fine: only the checksum catches those.
  std::printf("  %d of 300 forged payloads refused, the rest decoded to some layer\n", refused);
  EXPECT_GT(refused, 0);
}

TEST_F(MapFileFormat, ManifestRoundTrip) {
  const MapManifest m = test::smallManifest();
  ASSERT_EQ(m.validate(), "");
  std::string error;
  ASSERT_TRUE(writeManifest(m, dir_.path().string(), &error)) << error;
  const auto back = readManifest(dir_.path().string(), &error);
  ASSERT_TRUE(back) << error;
  EXPECT_EQ(back->generation, 3u);
  EXPECT_EQ(back->config.layer.voxel_size, m.config.layer.voxel_size);
  EXPECT_EQ(back->config.layer.voxels_per_side, 8);
  EXPECT_EQ(back->next_submap_id, 9);
  EXPECT_EQ(back->active_submap_id, std::optional<SubmapId>(8));
  EXPECT_EQ(back->counters, m.counters);
  ASSERT_EQ(back->submaps.size(), 2u);
  for (size_t i = 0; i < 2; ++i) {
    const SubmapRecord &x = m.submaps[i], &y = back->submaps[i];
    EXPECT_EQ(x.id, y.id);
    EXPECT_EQ(x.anchor_keyframe, y.anchor_keyframe);
    EXPECT_EQ(x.creation_time_ns, y.creation_time_ns);
    EXPECT_EQ(x.finished, y.finished);
    EXPECT_EQ(x.keyframe_ids, y.keyframe_ids);
    EXPECT_EQ(x.file, y.file);
    EXPECT_TRUE(x.T_G_M.translation() == y.T_G_M.translation());
    EXPECT_TRUE(x.T_G_M.rotation().coeffs().isApprox(y.T_G_M.rotation().coeffs(), 1e-15));
  }
  EXPECT_EQ(std::filesystem::file_size(dir_.file(kManifestFileName)), encodeManifest(m).size());
}

TEST_F(MapFileFormat, InconsistentManifestsAreNotWrittenOrRead) {
  const auto expectInvalid = [&](const MapManifest& m, const std::string& fragment) {
    const std::string problem = m.validate();
    EXPECT_NE(problem.find(fragment), std::string::npos) << problem;
    std::string error;
    EXPECT_FALSE(writeManifest(m, dir_.path().string(), &error));
    expectError(error, {dir_.file(kManifestFileName), "not written", fragment});
    // Forged with a valid header, it is refused on reading too.
    dir_.write(kManifestFileName, encodeManifest(m));
    EXPECT_FALSE(readManifest(dir_.path().string(), &error));
    expectError(error, {dir_.file(kManifestFileName), "inconsistent", fragment});
  };
  MapManifest m = test::smallManifest();
  m.submaps[1].id = 2;
  expectInvalid(m, "ids do not strictly increase");
  m = test::smallManifest();
  m.next_submap_id = 8;
  expectInvalid(m, "next submap id 8");
  m = test::smallManifest();
  m.submaps[0].file.file_name = "../../etc/passwd";
  expectInvalid(m, "file name \"../../etc/passwd\"");
  m = test::smallManifest();
  m.submaps[0].file.file_name = submapFileName(2, 4);  // newer than the manifest
  expectInvalid(m, "file name");
  m = test::smallManifest();
  m.submaps[0].finished = false;
  expectInvalid(m, "more than one unfinished submap");
  m = test::smallManifest();
  m.active_submap_id.reset();
  expectInvalid(m, "unfinished but no submap is active");
  m = test::smallManifest();
  m.active_submap_id = 2;
  expectInvalid(m, "the active submap 2 is not the one unfinished");
  m = test::smallManifest();
  m.submaps[0].keyframe_ids = {3, 21};
  expectInvalid(m, "lack the anchor");
  m = test::smallManifest();
  m.counters[""] = 1;
  expectInvalid(m, "counter name");
  m = test::smallManifest();
  m.config.layer.voxels_per_side = 5;
  expectInvalid(m, "voxels_per_side");
}

TEST_F(MapFileFormat, HostileManifestCountsAreRefusedBeforeAllocating) {
  std::string error;
  const std::string path = dir_.file(kManifestFileName);
  // Collection header with 2^32-1 submaps and nothing after it.
  std::string payload;
  ByteWriter w(&payload);
  w.u64(1);
  w.f32(0.02f);
  w.i32(8);
  w.i64(1);
  w.u8(0);
  w.i64(0);
  w.u32(0xffffffffu);
  dir_.write(kManifestFileName, sealMapFile(kManifestFileMagic, kManifestVersion, payload));
  EXPECT_FALSE(readManifest(dir_.path().string(), &error));
  expectError(error, {path, "submap count 4294967295 out of bounds"});

  // Every truncation of a valid manifest payload (resealed) is refused cleanly.
  const std::string full = encodeManifest(test::smallManifest()).substr(kMapFileHeaderBytes);
  for (size_t n = 0; n < full.size(); ++n) {
    dir_.write(kManifestFileName, sealMapFile(kManifestFileMagic, kManifestVersion,
                                                   full.substr(0, n)));
    EXPECT_FALSE(readManifest(dir_.path().string(), &error)) << n;
    EXPECT_NE(error.find(path), std::string::npos) << error;
  }
  // Huge keyframe count, huge file name length, huge counter count: patch the real bytes.
  const std::string good = encodeManifest(test::smallManifest());
  const size_t keyframe_count = kMapFileHeaderBytes + 37 + 24 + 56 + 1;
  dir_.write(kManifestFileName, good);
  std::string forged = full;
  forged.replace(keyframe_count - kMapFileHeaderBytes, 4, le32(0x7fffffff));
  dir_.write(kManifestFileName, sealMapFile(kManifestFileMagic, kManifestVersion, forged));
  EXPECT_FALSE(readManifest(dir_.path().string(), &error));
  expectError(error, {path, "keyframe count 2147483647 out of bounds"});
  forged = full;
  forged.replace(keyframe_count - kMapFileHeaderBytes + 4 + 3 * 8, 4, le32(0x7fffffff));
  dir_.write(kManifestFileName, sealMapFile(kManifestFileMagic, kManifestVersion, forged));
  EXPECT_FALSE(readManifest(dir_.path().string(), &error));
  expectError(error, {path, "file name length out of bounds"});
  forged = full;
  forged.append("junk");
  dir_.write(kManifestFileName, sealMapFile(kManifestFileMagic, kManifestVersion, forged));
  EXPECT_FALSE(readManifest(dir_.path().string(), &error));
  expectError(error, {path, "4 unexpected bytes"});
}

}  // namespace
}  // namespace cblox
