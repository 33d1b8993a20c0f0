// Saving and loading whole maps: round trips, incremental checkpoints, leftovers of
// interrupted writes, and corrupt or incomplete map directories.

#include "core/persistence/map_store.h"

#include <cstdio>
#include <filesystem>
#include <string>

#include <gtest/gtest.h>

#include "core/io/atomic_file.h"
#include "core/persistence/byte_codec.h"
#include "core/persistence/map_file_header.h"
#include "test/persistence/map_test_collection.h"
#include "test/test_support/temp_dir.h"

namespace cblox {
namespace {

namespace fs = std::filesystem;

const std::map<std::string, int64_t> kCounters = {
    {"frames_integrated", 1234}, {"fusions", 7}, {"negative", -9000000000}};

class MapStore : public ::testing::Test {
 protected:
  std::string dir() const { return dir_.path().string(); }
  std::string file(const std::string& name) const { return dir_.file(name); }

  // Loads dir() into a fresh collection; expects success.
  std::unique_ptr<SubmapCollection> load(MapLoadReport* report = nullptr) {
    std::string error;
    auto loaded = loadMap(dir(), report, &error);
    EXPECT_TRUE(loaded) << error;
    return loaded;
  }

  // Expects loading to fail with a message holding every fragment, leaving `into` empty.
  void expectLoadError(std::initializer_list<std::string> fragments) {
    SubmapCollection into(test::mapTestConfig());
    std::string error;
    EXPECT_FALSE(loadMap(dir(), &into, nullptr, &error));
    EXPECT_TRUE(into.empty());
    EXPECT_EQ(into.nextSubmapId(), 0);
    for (const std::string& f : fragments) {
      EXPECT_NE(error.find(f), std::string::npos) << "'" << f << "' not in: " << error;
    }
    std::printf("  rejected: %s\n", error.c_str());
  }

  // Saves the test collection; returns the manifest.
  MapManifest saveTestMap(const SubmapCollection& collection) {
    std::string error;
    MapSaveReport report;
    const auto manifest = saveMap(collection, dir(), kCounters, {}, &report, &error);
    EXPECT_TRUE(manifest) << error;
    EXPECT_EQ(report.files_written, collection.size());
    EXPECT_EQ(report.files_reused, 0u);
    return manifest.value_or(MapManifest{});
  }

  test::TempDir dir_{"cblox_mapstore"};
};

TEST_F(MapStore, RoundTripRestoresEverythingBitExact) {
  const auto original = test::buildTestCollection();
  ASSERT_EQ(original->submapIds(), (std::vector<SubmapId>{0, 1, 3, 4}));
  const MapManifest manifest = saveTestMap(*original);
  EXPECT_EQ(manifest.generation, 1u);
  EXPECT_EQ(manifest.active_submap_id, std::optional<SubmapId>(4));
  EXPECT_EQ(manifest.next_submap_id, 5);

  MapLoadReport report;
  const auto loaded = load(&report);
  ASSERT_TRUE(loaded);
  test::expectSameCollection(*original, *loaded);
  EXPECT_EQ(report.counters, kCounters);
  EXPECT_EQ(report.submaps, 4u);
  EXPECT_EQ(report.blocks, original->numBlocks());
  EXPECT_EQ(report.unlisted_files, 0u);
  EXPECT_EQ(report.generation, 1u);
  std::printf("  %zu blocks (%zu bytes in memory) in %llu bytes of files\n", original->numBlocks(),
              original->memoryBytes(), static_cast<unsigned long long>(report.bytes_read));

  // The loaded map behaves like the original: the active submap takes frames, pose updates
  // reach the anchored submap, and new ids continue after the removed submap 2.
  EXPECT_TRUE(loaded->activeSubmap()->lockForIntegration());
  EXPECT_FALSE(loaded->getSubmap(1)->lockForIntegration());
  const Transformationd Q = test::mapTestPose(0.1, {0, 0, 1}, {9, 9, 9});
  EXPECT_EQ(loaded->updateKeyframePoses({{10, Q}}).submaps_moved, 1u);
  EXPECT_TRUE(loaded->getSubmap(0)->T_G_M().isApprox(Q, 0.0));
  EXPECT_EQ(loaded->createSubmap(Transformationd(), 60, 6000)->id(), 5);

  // Save the loaded map again: the same voxel files (deterministic encoding).
  test::TempDir again("cblox_mapstore_again");
  const auto original_again = load();
  std::string error;
  const auto manifest2 =
      saveMap(*original_again, again.path().string(), kCounters, {}, nullptr, &error);
  ASSERT_TRUE(manifest2) << error;
  for (size_t i = 0; i < manifest.submaps.size(); ++i) {
    EXPECT_EQ(manifest2->submaps[i].file, manifest.submaps[i].file);
  }
}

TEST_F(MapStore, NoActiveSubmapAndEmptyCollection) {
  SubmapCollection empty(test::mapTestConfig());
  empty.reserveSubmapIds(3);
  std::string error;
  ASSERT_TRUE(saveMap(empty, dir(), {}, {}, nullptr, &error)) << error;
  auto loaded = load();
  ASSERT_TRUE(loaded);
  EXPECT_TRUE(loaded->empty());
  EXPECT_EQ(loaded->nextSubmapId(), 3);

  const auto original = test::buildTestCollection();
  original->finishActiveSubmap();
  ASSERT_TRUE(saveMap(*original, dir(), {}, {}, nullptr, &error)) << error;
  loaded = load();
  ASSERT_TRUE(loaded);
  EXPECT_EQ(loaded->activeSubmap(), nullptr);
  test::expectSameCollection(*original, *loaded);
}

// Incremental checkpoint: only the listed submap is rewritten (new generation), the others
// keep their files; pose-only changes travel in the manifest; superseded files are removed.
TEST_F(MapStore, IncrementalCheckpointRewritesOnlyTheListedSubmaps) {
  const auto collection = test::buildTestCollection();
  const MapManifest first = saveTestMap(*collection);

  // Submap 1 (finished) gets new voxels; submap 0 only a new pose; a keyframe joins 3.
  {
    Submap& s1 = *collection->getSubmap(1);
    s1.mutableLayer()->allocateBlock(BlockIndex(40, 40, 40))->voxel(7) =
        TsdfVoxel{0.25f, 9.0f, Color{4, 5, 6}};
    s1.refreshStatistics();
  }
  collection->updateKeyframePoses({{10, test::mapTestPose(1.0, {0, 1, 1}, {5, 6, 7})}});
  collection->getSubmap(3)->addKeyframe(41);
  const auto s1_file = first.submaps[1].file.file_name;

  std::string error;
  MapSaveReport report;
  const auto second =
      writeMapCheckpoint(*collection, dir(), &first, {1}, {{"checkpoints", 2}}, {}, &report, &error);
  ASSERT_TRUE(second) << error;
  EXPECT_EQ(second->generation, 2u);
  EXPECT_EQ(report.files_written, 1u);
  EXPECT_EQ(report.files_reused, 3u);
  EXPECT_EQ(report.files_removed, 1u);  // submap_1_g1
  EXPECT_EQ(second->submaps[1].file.file_name, submapFileName(1, 2));
  EXPECT_EQ(second->submaps[0].file, first.submaps[0].file);
  EXPECT_FALSE(fs::exists(file(s1_file)));

  MapLoadReport load_report;
  auto loaded = load(&load_report);
  ASSERT_TRUE(loaded);
  test::expectSameCollection(*collection, *loaded);
  EXPECT_EQ(load_report.counters, (std::map<std::string, int64_t>{{"checkpoints", 2}}));

  // A removed submap drops out of the next checkpoint, its file is removed; a new one is
  // written even though it is not listed (it has no file yet).
  collection->removeSubmap(3);
  collection->createSubmap(Transformationd(), 70, 7000);
  const auto third = writeMapCheckpoint(*collection, dir(), &*second, {}, {}, {}, &report, &error);
  ASSERT_TRUE(third) << error;
  EXPECT_EQ(report.files_written, 1u);  // submap 5
  EXPECT_EQ(report.files_reused, 3u);
  EXPECT_EQ(report.files_removed, 1u);  // submap_3_g1
  loaded = load();
  ASSERT_TRUE(loaded);
  test::expectSameCollection(*collection, *loaded);
  size_t files = 0;
  for ([[maybe_unused]] const auto& entry : fs::directory_iterator(dir())) ++files;
  EXPECT_EQ(files, 5u);  // four submap files and the manifest
}

// A checkpoint interrupted after writing submap files but before the manifest (a crash),
// and leftover temporary files, leave the previous map loadable as it was; the next
// checkpoint does not reuse the generation of the orphaned files and clears them.
TEST_F(MapStore, InterruptedCheckpointLeavesThePreviousMap) {
  const auto collection = test::buildTestCollection();
  const MapManifest first = saveTestMap(*collection);
  const auto before = load();
  ASSERT_TRUE(before);

  collection->getSubmap(4)->lockForIntegration().layer().allocateBlock(BlockIndex(-9, -9, -9));
  std::string error;
  ASSERT_TRUE(writeSubmapFile(*collection->getSubmap(4), dir(), 2, &error)) << error;
  dir_.write(kManifestFileName + std::string(".tmp.999.0"), "half a manifest");
  dir_.write(submapFileName(0, 2) + ".tmp.999.1", "half a submap");

  MapLoadReport report;
  const auto loaded = load(&report);
  ASSERT_TRUE(loaded);
  test::expectSameCollection(*before, *loaded);
  EXPECT_EQ(loaded->getSubmap(4)->layer().getBlock(BlockIndex(-9, -9, -9)), nullptr);
  EXPECT_EQ(report.unlisted_files, 3u);

  MapSaveReport save;
  const auto second = writeMapCheckpoint(*collection, dir(), &first, {4}, {}, {}, &save, &error);
  ASSERT_TRUE(second) << error;
  EXPECT_EQ(second->generation, 3u);  // above the orphan's generation 2
  EXPECT_EQ(save.files_removed, 4u);  // the orphan, two temporaries, submap_4_g1
  const auto after = load(&report);
  ASSERT_TRUE(after);
  test::expectSameCollection(*collection, *after);
  EXPECT_EQ(report.unlisted_files, 0u);
}

TEST_F(MapStore, CorruptOrIncompleteMapsAreRefusedWithTheFileNamed) {
  const auto collection = test::buildTestCollection();
  const MapManifest manifest = saveTestMap(*collection);
  const std::string manifest_path = file(kManifestFileName);
  const std::string s1 = file(manifest.submaps[1].file.file_name);
  const std::string s1_bytes = test::readFile(s1);
  const std::string manifest_bytes = test::readFile(manifest_path);
  const auto restore = [&] {
    ASSERT_TRUE(writeFileAtomically(s1, s1_bytes, nullptr));
    ASSERT_TRUE(writeFileAtomically(manifest_path, manifest_bytes, nullptr));
  };

  // A flipped byte in a submap file's payload.
  std::string bytes = s1_bytes;
  bytes[kMapFileHeaderBytes + bytes.size() / 2 - 16] ^= 0x20;
  ASSERT_TRUE(writeFileAtomically(s1, bytes, nullptr));
  expectLoadError({s1, "checksum mismatch"});
  restore();

  // A valid submap file that is not the one the manifest lists (another content).
  const auto other = test::buildTestCollection();
  other->getSubmap(1)->mutableLayer()->allocateBlock(BlockIndex(0, 0, 99));
  ASSERT_TRUE(writeSubmapFile(*other->getSubmap(1), dir(), 1, nullptr));
  expectLoadError({s1, "checksum mismatch with the manifest"});
  restore();

  // Truncated submap file.
  ASSERT_TRUE(writeFileAtomically(s1, s1_bytes.substr(0, s1_bytes.size() - 100), nullptr));
  expectLoadError({s1, "truncated"});
  restore();

  // Missing submap file.
  fs::remove(s1);
  expectLoadError({s1, "cannot open submap file", "No such file"});
  restore();

  // Bad magic, newer version, truncation of the manifest.
  ASSERT_TRUE(writeFileAtomically(manifest_path, "CBLOXSUB" + manifest_bytes.substr(8), nullptr));
  expectLoadError({manifest_path, "bad magic"});
  std::string newer = manifest_bytes;
  newer.replace(8, 4, std::string("\xe7\x03\0\0", 4));  // 999
  ASSERT_TRUE(writeFileAtomically(manifest_path, newer, nullptr));
  expectLoadError({manifest_path,
                   "map manifest format version 999 is newer than this reader supports (" +
                       std::to_string(kManifestVersion) + ")"});
  ASSERT_TRUE(writeFileAtomically(manifest_path, manifest_bytes.substr(0, 40), nullptr));
  expectLoadError({manifest_path, "truncated"});
  restore();

  // No manifest at all (a directory that is no map, or a map whose first save crashed).
  fs::remove(manifest_path);
  expectLoadError({manifest_path, "cannot open map manifest"});
  restore();

  // Loading into a collection that is not empty, or of another geometry.
  SubmapCollection busy(test::mapTestConfig());
  busy.createSubmap(Transformationd(), 1, 0);
  std::string error;
  EXPECT_FALSE(loadMap(dir(), &busy, nullptr, &error));
  EXPECT_NE(error.find("not empty"), std::string::npos) << error;
  EXPECT_EQ(busy.size(), 1u);
  SubmapCollectionConfig coarse = test::mapTestConfig();
  coarse.layer.voxel_size = 0.05f;
  SubmapCollection other_geometry(coarse);
  EXPECT_FALSE(loadMap(dir(), &other_geometry, nullptr, &error));
  EXPECT_NE(error.find("layer geometry"), std::string::npos) << error;
  EXPECT_TRUE(other_geometry.empty());

  // Everything restored: it loads again.
  EXPECT_TRUE(load());
}

TEST_F(MapStore, SaveErrorsNameThePath) {
  const auto collection = test::buildTestCollection();
  dir_.write("not_a_dir", "x");
  std::string error;
  EXPECT_FALSE(saveMap(*collection, file("not_a_dir"), {}, {}, nullptr, &error));
  EXPECT_NE(error.find(file("not_a_dir")), std::string::npos) << error;
  std::printf("  rejected: %s\n", error.c_str());
  EXPECT_FALSE(saveMap(*collection, file("not_a_dir/sub"), {}, {}, nullptr, &error));
  EXPECT_NE(error.find(file("not_a_dir/sub")), std::string::npos) << error;
  std::printf("  rejected: %s\n", error.c_str());
  // A counter name the format cannot hold: nothing is committed.
  EXPECT_FALSE(saveMap(*collection, file("map"), {{std::string(300, 'c'), 1}}, {}, nullptr, &error));
  EXPECT_NE(error.find("counter name"), std::string::npos) << error;
  EXPECT_FALSE(fs::exists(file("map/manifest.cbmap")));
}

}  // namespace
}  // namespace cblox
