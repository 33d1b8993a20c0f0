// FusionExportWorker: a pair is fused even when one of its subvolumes is still being finished.

#include <gtest/gtest.h>

#include <chrono>
#include <condition_variable>
#include <filesystem>
#include <mutex>
#include <thread>
#include <vector>

#include "core/mapping/fusion_export_worker.h"
#include "core/mapping/mapper_config.h"

namespace cblox {
namespace {

using std::chrono::milliseconds;

// SubmapCollection::createSubmap makes the new subvolume active, then finishes the previous
// one outside its lock, which waits for the frame being integrated. A pair naming that
// previous subvolume, taken in the moment between (map maintenance saw the new active one),
// waits for the frame and is fused: it is not failed as "still active" (which counted the
// pair twice, accepted once more after the retry back-off).
TEST(FusionExportWorkerTest, FusesASubvolumeThatIsStillBeingFinished) {
  const MapperConfig mapper;
  SubmapCollection collection(SubmapCollectionConfig{mapper.layer});
  const std::shared_ptr<Submap> older = collection.createSubmap(Transformationd(), 10, 0);
  const std::shared_ptr<Submap> newer = collection.createSubmap(Transformationd(), 11, 1);
  ASSERT_TRUE(older->isFinished());
  Submap::WriteLock frame = newer->lockForIntegration();  // the integrator's frame in hand
  ASSERT_TRUE(frame);
  std::thread replace([&] { collection.createSubmap(Transformationd(), 12, 2); });
  while (collection.activeSubmap() == newer) std::this_thread::sleep_for(milliseconds(1));
  EXPECT_FALSE(newer->isFinished());  // replaced, and waiting for the frame to finish it

  std::mutex mutex;
  std::condition_variable done;
  std::vector<bool> results;
  FusionExportWorkerConfig config{MapExportConfig{mapper.layer, mapper.fusion, mapper.mesh},
                                  std::filesystem::temp_directory_path(), 4, 0, false};
  FusionExportWorker worker(
      &collection, config,
      [&](const FusionPair&, bool fused) {
        std::lock_guard<std::mutex> lock(mutex);
        results.push_back(fused);
        done.notify_all();
      },
      [](const std::string&) {});
  worker.start();
  FusionPair pair;
  pair.older = older->id();
  pair.newer = newer->id();
  pair.older_keyframe = 10;
  pair.newer_keyframe = 11;
  worker.submitFusions({pair});
  std::this_thread::sleep_for(milliseconds(200));
  {
    std::lock_guard<std::mutex> lock(mutex);
    EXPECT_TRUE(results.empty()) << "the pair was decided before the frame in hand was done";
  }
  frame.unlock();  // the frame is integrated: both finish() calls return
  replace.join();
  {
    std::unique_lock<std::mutex> lock(mutex);
    ASSERT_TRUE(done.wait_for(lock, std::chrono::seconds(10), [&] { return !results.empty(); }));
    ASSERT_EQ(results.size(), 1u);
    EXPECT_TRUE(results[0]);
  }
  EXPECT_TRUE(newer->isFinished());
  EXPECT_EQ(collection.getSubmap(pair.newer), nullptr);  // fused into the older one
  EXPECT_EQ(older->keyframeIds(), (std::vector<KeyframeId>{10, 11}));
  EXPECT_EQ(collection.activeSubmap()->anchorKeyframe(), 12);
  worker.stop();
}

}  // namespace
}  // namespace cblox
