// Manifest format version 3: the map maintenance section (the keyframes' covisibility landmark
// sets and pair back-offs) round trip, version 1 and 2 manifests, and hostile or inconsistent
// sections; and the section through saveMap / loadMap / MapCheckpointer.

#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <limits>
#include <string>

#include <gtest/gtest.h>

#include "core/io/atomic_file.h"
#include "core/persistence/byte_codec.h"
#include "core/persistence/map_checkpointer.h"
#include "core/persistence/map_file_header.h"
#include "core/persistence/map_manifest.h"
#include "core/persistence/map_store.h"
#include "test/persistence/map_test_collection.h"
#include "test/test_support/temp_dir.h"

namespace cblox {
namespace {

using persistence_detail::ByteWriter;

constexpr uint64_t kMaxId = std::numeric_limits<uint64_t>::max();
constexpr int64_t kUnknown = KeyframeLandmarks::kUnknownKeyframe;

// A subvolume whose keyframes each observed the given landmarks.
SubvolumeLandmarks subvolume(int64_t id, std::vector<KeyframeLandmarks> keyframes) {
  return SubvolumeLandmarks{id, std::move(keyframes)};
}

// smallManifest() with a maintenance section that covers the varint edge cases.
MapManifest withMaintenance() {
  MapManifest m = test::smallManifest();
  m.maintenance.subvolumes = {
      subvolume(2, {{4, {0, 1, 127, 128, 16383, 16384}},
                    {7, {uint64_t{1} << 40, uint64_t{1} << 63, kMaxId}}}),
      subvolume(8, {})};
  m.maintenance.backoffs = {{2, 8, 3, 1.5}};
  return m;
}

// The payload of `m` and the offset at which its maintenance section begins.
std::string payloadOf(const MapManifest& m, size_t* section = nullptr) {
  const std::string payload = encodeManifest(m).substr(kMapFileHeaderBytes);
  if (section != nullptr) {
    MapManifest bare = m;
    bare.maintenance = {};
    *section = encodeManifest(bare).size() - kMapFileHeaderBytes - 8;  // two empty counts
  }
  return payload;
}

class ManifestMaintenance : public ::testing::Test {
 protected:
  std::string dir() const { return dir_.path().string(); }
  std::string path() const { return dir_.file(kManifestFileName); }

  // Writes a manifest with `payload` sealed as `version`; returns readManifest's error ("" if
  // it was read).
  std::string readForged(const std::string& payload, uint32_t version = kManifestVersion) {
    dir_.write(kManifestFileName, sealMapFile(kManifestFileMagic, version, payload));
    std::string error;
    if (readManifest(dir(), &error)) return "";
    EXPECT_NE(error.find(path()), std::string::npos) << error;
    std::printf("  rejected: %s\n", error.c_str());
    return error;
  }

  test::TempDir dir_{"cblox_manifest_v3"};
};

TEST_F(ManifestMaintenance, RoundTripIsExact) {
  const MapManifest m = withMaintenance();
  ASSERT_EQ(m.validate(), "");
  std::string error;
  ASSERT_TRUE(writeManifest(m, dir(), &error)) << error;
  const auto back = readManifest(dir(), &error);
  ASSERT_TRUE(back) << error;
  EXPECT_EQ(back->maintenance, m.maintenance);
  EXPECT_EQ(back->counters, m.counters);
  // Everything else too: the same manifest encodes to the same bytes.
  EXPECT_EQ(encodeManifest(*back), encodeManifest(m));
  // Version 3 on disk.
  const std::string bytes = test::readFile(path());
  EXPECT_EQ(bytes.substr(8, 4), std::string("\x03\x00\x00\x00", 4));
  // Ascending ids cost their differences: 6 ids in 1+1+1+1+2+1 bytes, 3 in 6+9+9; each keyframe
  // 8 + 4 bytes more, each subvolume 8 + 4.
  size_t section = 0;
  const std::string payload = payloadOf(m, &section);
  EXPECT_EQ(payload.size() - section,
            4u + (8 + 4 + (8 + 4 + 7) + (8 + 4 + 24)) + (8 + 4) + 4u + 28u);
}

TEST_F(ManifestMaintenance, Version2SetsReadAsOfAKeyframeNotKnown) {
  size_t section = 0;
  std::string v2 = payloadOf(test::smallManifest(), &section).substr(0, section);
  ByteWriter w(&v2);
  w.u32(2);  // subvolumes 2 and 8, one landmark set each
  w.i64(2);
  w.u32(3);
  w.uvarint(5);
  w.uvarint(1);
  w.uvarint(300);
  w.i64(8);
  w.u32(0);
  w.u32(1);  // one back-off
  w.i64(2);
  w.i64(8);
  w.i32(1);
  w.f64(0.5);
  ASSERT_EQ(readForged(v2, 2), "");
  std::string error;
  const auto back = readManifest(dir(), &error);
  ASSERT_TRUE(back) << error;
  ASSERT_EQ(back->maintenance.subvolumes.size(), 2u);
  EXPECT_EQ(back->maintenance.subvolumes[0], subvolume(2, {{kUnknown, {5, 6, 306}}}));
  EXPECT_EQ(back->maintenance.subvolumes[1], subvolume(8, {{kUnknown, {}}}));
  ASSERT_EQ(back->maintenance.backoffs.size(), 1u);
  EXPECT_EQ(back->maintenance.backoffs[0], (FusionPairBackoff{2, 8, 1, 0.5}));
  // Written again, it is version 3 and reads back the same.
  ASSERT_TRUE(writeManifest(*back, dir(), &error)) << error;
  EXPECT_EQ(readManifest(dir(), &error)->maintenance, back->maintenance);
}

TEST_F(ManifestMaintenance, Version1ManifestsReadWithAnEmptySection) {
  MapManifest m = test::smallManifest();
  size_t section = 0;
  const std::string v2 = payloadOf(m, &section);
  const std::string v1 = v2.substr(0, section);  // what version 1 wrote
  ASSERT_EQ(readForged(v1, 1), "");
  std::string error;
  const auto back = readManifest(dir(), &error);
  ASSERT_TRUE(back) << error;
  EXPECT_TRUE(back->maintenance.empty());
  EXPECT_EQ(encodeManifest(*back), encodeManifest(m));
  // A version 1 manifest has nothing after its counters.
  EXPECT_NE(readForged(v2, 1).find("8 unexpected bytes after the counters"), std::string::npos);
  // A newer version than this reader's is refused with the version message.
  EXPECT_NE(readForged(v2, kManifestVersion + 1)
                .find("format version 4 is newer than this reader supports (3)"),
            std::string::npos);
}

TEST_F(ManifestMaintenance, TruncatedOrCorruptSectionsAreRefused) {
  size_t section = 0;
  const std::string full = payloadOf(withMaintenance(), &section);
  // Every cut inside the section (resealed, so the checksum holds) is refused.
  for (size_t n = section; n < full.size(); ++n) {
    EXPECT_NE(readForged(full.substr(0, n)), "") << n;
  }
  // A flipped byte without resealing: the checksum says so.
  std::string bytes = encodeManifest(withMaintenance());
  bytes[kMapFileHeaderBytes + section + 13] ^= 0x40;
  dir_.write(kManifestFileName, bytes);
  std::string error;
  EXPECT_FALSE(readManifest(dir(), &error));
  EXPECT_NE(error.find("checksum mismatch"), std::string::npos) << error;
  // Bytes after the section.
  EXPECT_NE(readForged(full + "x").find("1 unexpected bytes after the maintenance section"),
            std::string::npos);
}

TEST_F(ManifestMaintenance, HostileCountsAndIdsAreRefusedBeforeAllocating) {
  size_t section = 0;
  const MapManifest bare = test::smallManifest();
  const std::string head = payloadOf(bare, &section).substr(0, section);
  const auto forged = [&](auto&& write) {
    std::string payload = head;
    ByteWriter w(&payload);
    write(w);
    return readForged(payload);
  };
  EXPECT_NE(forged([](ByteWriter& w) {
              w.u32(0xffffffffu);
            }).find("maintenance subvolume count 4294967295 out of bounds"),
            std::string::npos);
  EXPECT_NE(forged([](ByteWriter& w) {
              w.u32(1);
              w.i64(2);
              w.u32(0x7fffffffu);
              w.i64(4);
            }).find("keyframe count 2147483647 out of bounds"),
            std::string::npos);
  EXPECT_NE(forged([](ByteWriter& w) {
              w.u32(1);
              w.i64(2);
              w.u32(1);
              w.i64(4);
              w.u32(0x7fffffffu);
              w.uvarint(1);
            }).find("landmark count 2147483647 out of bounds"),
            std::string::npos);
  EXPECT_NE(forged([](ByteWriter& w) {  // 11 continuation bytes: no uvarint is that long
              w.u32(1);
              w.i64(2);
              w.u32(1);
              w.i64(4);
              w.u32(1);
              w.bytes(std::string(11, '\xff'));
              w.u32(0);
            })
                .find("truncated or malformed landmark id 0"),
            std::string::npos);
  EXPECT_NE(forged([](ByteWriter& w) {  // 10 bytes whose last carries bits above 2^64
              w.u32(1);
              w.i64(2);
              w.u32(1);
              w.i64(4);
              w.u32(1);
              w.bytes(std::string(9, '\xff') + "\x02");
              w.u32(0);
            })
                .find("truncated or malformed landmark id 0"),
            std::string::npos);
  EXPECT_NE(forged([](ByteWriter& w) {  // a repeated id: difference 0
              w.u32(1);
              w.i64(2);
              w.u32(1);
              w.i64(4);
              w.u32(2);
              w.uvarint(5);
              w.uvarint(0);
              w.u32(0);
            })
                .find("landmark id 1 does not increase (difference 0)"),
            std::string::npos);
  EXPECT_NE(forged([](ByteWriter& w) {  // past 2^64 - 1
              w.u32(1);
              w.i64(2);
              w.u32(1);
              w.i64(4);
              w.u32(2);
              w.uvarint(kMaxId);
              w.uvarint(1);
              w.u32(0);
            })
                .find("landmark id 1 does not increase"),
            std::string::npos);
  EXPECT_NE(forged([](ByteWriter& w) {
              w.u32(0);
              w.u32(0x10000000u);
            }).find("back-off count 268435456 out of bounds"),
            std::string::npos);
  EXPECT_NE(forged([](ByteWriter& w) {
              w.u32(0);
              w.u32(1);
              w.i64(2);
              w.i64(8);
              w.i32(1);
            }).find("back-off count 1 out of bounds for the 20 bytes that remain"),
            std::string::npos);
}

TEST_F(ManifestMaintenance, InconsistentSectionsAreNotWrittenOrRead) {
  const auto expectInvalid = [&](const MapManifest& m, const std::string& fragment) {
    std::string error;
    EXPECT_FALSE(writeManifest(m, dir(), &error));
    EXPECT_NE(error.find(fragment), std::string::npos) << error;
    EXPECT_NE(readForged(encodeManifest(m).substr(kMapFileHeaderBytes)).find(fragment),
              std::string::npos);
  };
  MapManifest m = withMaintenance();
  m.maintenance.subvolumes[0].subvolume = 3;  // not listed (submaps are 2 and 8)
  expectInvalid(m, "maintenance: subvolume 3 is not a listed submap");
  m = withMaintenance();
  m.maintenance.backoffs[0].newer = 9;
  expectInvalid(m, "names a submap that is not listed");
  m = withMaintenance();
  m.maintenance.backoffs[0].retry_in_s = -1.0;
  expectInvalid(m, "retry_in_s");
  m = withMaintenance();
  std::swap(m.maintenance.subvolumes[0], m.maintenance.subvolumes[1]);
  expectInvalid(m, "subvolume ids do not strictly increase");
  m = withMaintenance();
  std::swap(m.maintenance.subvolumes[0].keyframes[0], m.maintenance.subvolumes[0].keyframes[1]);
  expectInvalid(m, "keyframe 4: keyframe ids do not strictly increase");
  m = withMaintenance();
  m.maintenance.subvolumes[0].keyframes[0].keyframe = -2;
  expectInvalid(m, "keyframe -2: keyframe id is negative");
}

TEST_F(ManifestMaintenance, SaveLoadAndCheckpointsCarryTheStateOfListedSubmaps) {
  const auto collection = test::buildTestCollection();  // submaps 0, 1, 3, 4
  FusionSchedulerState state;
  // 2 was removed (fused) and 9 does not exist yet: neither goes into the manifest.
  state.subvolumes = {subvolume(0, {{0, {1, 5}}, {3, {5, 9}}}), subvolume(1, {{5, {5, 6}}}),
                      subvolume(2, {{7, {7}}}), subvolume(4, {{kUnknown, {uint64_t{1} << 50}}}),
                      subvolume(9, {{20, {1}}})};
  state.backoffs = {{0, 1, 2, 0.25}, {0, 2, 1, 0.0}, {1, 9, 1, 2.0}, {3, 4, 0, 4.0}};
  FusionSchedulerState listed = state;
  listed.subvolumes = {state.subvolumes[0], state.subvolumes[1], state.subvolumes[3]};
  listed.backoffs = {state.backoffs[0], state.backoffs[3]};

  std::string error;
  ASSERT_TRUE(saveMap(
      *collection, dir(), {}, [&] { return state; }, nullptr, &error))
      << error;
  MapLoadReport report;
  ASSERT_TRUE(loadMap(dir(), &report, &error)) << error;
  EXPECT_EQ(report.maintenance, listed);
  test::expectSameCollection(*collection, *loadMap(dir(), nullptr, &error));

  // The checkpointer asks for the state once per checkpoint, after the map's snapshot.
  test::TempDir checkpoints("cblox_manifest_v3_ckpt");
  MapCheckpointer checkpointer(checkpoints.path().string());
  int asked = 0;
  state.backoffs.clear();
  ASSERT_TRUE(checkpointer.checkpoint(
      *collection, {},
      [&] {
        ++asked;
        return state;
      },
      &error))
      << error;
  EXPECT_EQ(asked, 1);
  const auto manifest = readManifest(checkpoints.path().string(), &error);
  ASSERT_TRUE(manifest) << error;
  EXPECT_EQ(manifest->maintenance.subvolumes, listed.subvolumes);
  EXPECT_TRUE(manifest->maintenance.backoffs.empty());
  EXPECT_EQ(checkpointer.lastManifest()->maintenance, manifest->maintenance);

  // A source that gives an inconsistent state: nothing is committed.
  FusionSchedulerState bad;
  bad.subvolumes = {subvolume(1, {{5, {3, 3}}})};
  EXPECT_FALSE(checkpointer.checkpoint(
      *collection, {}, [&] { return bad; }, &error));
  EXPECT_NE(error.find("the maintenance state is inconsistent"), std::string::npos) << error;
  EXPECT_EQ(readManifest(checkpoints.path().string(), nullptr)->generation, manifest->generation);
}

}  // namespace
}  // namespace cblox
