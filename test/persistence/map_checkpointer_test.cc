// Incremental checkpoints by submap revision (MapCheckpointer): everything the first time, then
// only the submaps whose layer changed, nothing but the manifest when nothing changed, and a
// manifest that drops removed submaps; every checkpoint loads back equal to the collection.

#include "core/persistence/map_checkpointer.h"

#include <filesystem>
#include <fstream>
#include <map>
#include <string>

#include <gtest/gtest.h>

#include "core/persistence/map_store.h"
#include "test/persistence/map_test_collection.h"
#include "test/test_support/temp_dir.h"

namespace cblox {
namespace {

const std::map<std::string, int64_t> kCounters = {{"frames_integrated", 12}};

MapCheckpointReport checkpointOk(MapCheckpointer* checkpointer,
                                 const SubmapCollection& collection) {
  std::string error;
  const std::optional<MapCheckpointReport> report =
      checkpointer->checkpoint(collection, kCounters, {}, &error);
  EXPECT_TRUE(report) << error;
  return report.value_or(MapCheckpointReport{});
}

void expectLoadsEqual(const std::string& dir, const SubmapCollection& collection) {
  std::string error;
  MapLoadReport load;
  const auto loaded = loadMap(dir, &load, &error);
  ASSERT_TRUE(loaded) << error;
  test::expectSameCollection(collection, *loaded);
  EXPECT_EQ(load.counters, kCounters);
  EXPECT_EQ(load.unlisted_files, 0u);  // superseded files are removed
}

TEST(MapCheckpointer, WritesOnlyNewAndChangedSubmaps) {
  test::TempDir dir("cblox_checkpointer");
  const std::unique_ptr<SubmapCollection> collection = test::buildTestCollection();
  ASSERT_EQ(collection->size(), 4u);  // 0, 1, 3 finished, 4 active
  MapCheckpointer checkpointer(dir.path().string());
  EXPECT_FALSE(checkpointer.lastManifest());

  // First: every submap.
  const MapCheckpointReport first = checkpointOk(&checkpointer, *collection);
  EXPECT_EQ(first.submaps, 4u);
  EXPECT_EQ(first.submaps_written, 4u);
  EXPECT_EQ(first.submaps_reused, 0u);
  EXPECT_GT(first.bytes_written, 0u);
  ASSERT_TRUE(checkpointer.lastManifest());
  EXPECT_EQ(checkpointer.lastManifest()->generation, first.generation);
  expectLoadsEqual(checkpointer.dir(), *collection);

  // Nothing changed (a pose update is metadata: it goes into the manifest only).
  collection->updateKeyframePoses({{10, test::mapTestPose(0.12, {0, 0, 1}, {0.1, 0.2, 0.3})}});
  const MapCheckpointReport unchanged = checkpointOk(&checkpointer, *collection);
  EXPECT_GT(unchanged.generation, first.generation);
  EXPECT_EQ(unchanged.submaps_written, 0u);
  EXPECT_EQ(unchanged.submaps_reused, 4u);
  EXPECT_GT(unchanged.bytes_written, 0u);  // the manifest
  expectLoadsEqual(checkpointer.dir(), *collection);

  // A frame into the active submap: that one only.
  {
    Submap::WriteLock lock = collection->getSubmap(4)->lockForIntegration();
    ASSERT_TRUE(lock);
    lock.layer().allocateBlock(BlockIndex(20, 20, 20))->voxel(0) =
        TsdfVoxel{0.01f, 2.0f, Color{1, 2, 3}};
  }
  const MapCheckpointReport one = checkpointOk(&checkpointer, *collection);
  EXPECT_EQ(one.submaps_written, 1u);
  EXPECT_EQ(one.submaps_reused, 3u);
  expectLoadsEqual(checkpointer.dir(), *collection);

  // A fusion-like write into a finished submap, a removed submap and a new one.
  collection->getSubmap(0)->mutableLayer()->allocateBlock(BlockIndex(-20, 0, 0));
  collection->getSubmap(0)->refreshStatistics();
  collection->removeSubmap(3);
  collection->createSubmap(Transformationd(), 60, 6000);  // id 5; finishes 4
  const MapCheckpointReport changed = checkpointOk(&checkpointer, *collection);
  EXPECT_EQ(changed.submaps, 4u);          // 0, 1, 4, 5: 3 is no longer listed
  EXPECT_EQ(changed.submaps_written, 2u);  // 0 (changed) and 5 (new)
  EXPECT_EQ(changed.submaps_reused, 2u);
  expectLoadsEqual(checkpointer.dir(), *collection);
}

// A resume: the collection loaded from the checkpoint directory is adopted, and the next
// checkpoint lists the loaded files again; a frame into one submap then writes only it.
TEST(MapCheckpointer, AfterAResumeTheLoadedFilesAreReused) {
  test::TempDir dir("cblox_checkpointer_resume");
  const std::unique_ptr<SubmapCollection> original = test::buildTestCollection();
  MapCheckpointer first(dir.path().string());
  checkpointOk(&first, *original);

  std::string error;
  MapLoadReport load;
  const std::unique_ptr<SubmapCollection> loaded = loadMap(dir.path().string(), &load, &error);
  ASSERT_TRUE(loaded) << error;
  const std::optional<MapManifest> manifest = readManifest(dir.path().string(), &error);
  ASSERT_TRUE(manifest) << error;
  MapCheckpointer resumed(dir.path().string());
  resumed.adoptLoaded(*manifest, *loaded);
  const MapCheckpointReport again = checkpointOk(&resumed, *loaded);
  EXPECT_EQ(again.submaps_written, 0u);
  EXPECT_EQ(again.submaps_reused, 4u);
  EXPECT_GT(again.generation, manifest->generation);
  expectLoadsEqual(resumed.dir(), *original);

  loaded->getSubmap(4)->mutableLayer();  // a fusion-style write: the revision moves
  const MapCheckpointReport changed = checkpointOk(&resumed, *loaded);
  EXPECT_EQ(changed.submaps_written, 1u);
  EXPECT_EQ(changed.submaps_reused, 3u);
}

TEST(MapCheckpointer, AFailedCheckpointIsRetriedInFull) {
  test::TempDir dir("cblox_checkpointer");
  const std::unique_ptr<SubmapCollection> collection = test::buildTestCollection();
  // The directory path is a regular file: nothing can be written.
  const std::string blocked = dir.file("blocked");
  { std::ofstream(blocked) << "x"; }
  MapCheckpointer failing(blocked);
  std::string error;
  EXPECT_FALSE(failing.checkpoint(*collection, kCounters, {}, &error));
  EXPECT_NE(error.find("blocked"), std::string::npos) << error;
  EXPECT_FALSE(failing.lastManifest());
  std::filesystem::remove(blocked);
  const MapCheckpointReport retried = checkpointOk(&failing, *collection);
  EXPECT_EQ(retried.submaps_written, 4u);
  expectLoadsEqual(blocked, *collection);
}

}  // namespace
}  // namespace cblox
