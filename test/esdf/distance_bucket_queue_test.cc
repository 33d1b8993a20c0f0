#include "core/esdf/distance_bucket_queue.h"

#include <gtest/gtest.h>

#include <cstdint>
#include <utility>
#include <vector>

namespace cblox {
namespace {

TEST(DistanceBucketQueue, PopsTheSmallestKeyFirstAndClampsKeysIntoTheLastBucket) {
  DistanceBucketQueue<int> queue(10);
  queue.push(7, 70);
  queue.push(3, 30);
  queue.push(50, 500);  // beyond the bound: the last bucket (key 10)
  queue.push(3, 31);
  std::vector<std::pair<uint32_t, int>> popped;
  while (!queue.empty()) {
    int entry = 0;
    uint32_t key = 0;
    queue.pop(&entry, &key);
    popped.emplace_back(key, entry);
  }
  const std::vector<std::pair<uint32_t, int>> expected = {{3, 31}, {3, 30}, {7, 70}, {10, 500}};
  EXPECT_EQ(popped, expected);
}

TEST(DistanceBucketQueue, PeakCountsTheMostEntriesHeldSinceTheReset) {
  DistanceBucketQueue<int> queue(4);
  for (int i = 0; i < 5; ++i) queue.push(1, i);
  int entry = 0;
  uint32_t key = 0;
  for (int i = 0; i < 3; ++i) queue.pop(&entry, &key);
  EXPECT_EQ(queue.size(), 2u);
  EXPECT_EQ(queue.peakSize(), 5u);
  queue.resetPeak();
  EXPECT_EQ(queue.peakSize(), 2u);
  queue.push(2, 9);
  EXPECT_EQ(queue.peakSize(), 3u);
}

TEST(DistanceBucketQueue, AWaveMovingThroughTheKeysReusesTheChunksItPassed) {
  using Queue = DistanceBucketQueue<int>;
  Queue queue(100);
  const size_t chunks_for_1000 = (1000 + Queue::kChunkEntries - 1) / Queue::kChunkEntries;
  int entry = 0;
  uint32_t key = 0;
  for (uint32_t k = 0; k <= 100; ++k) {
    for (int i = 0; i < 1000; ++i) queue.push(k, i);
    for (int i = 0; i < 1000; ++i) queue.pop(&entry, &key);
    ASSERT_EQ(key, k);
    // Storage follows the entries held at once (1000), not the 101000 ever pushed.
    EXPECT_EQ(queue.capacity(), chunks_for_1000 * Queue::kChunkEntries) << "key " << k;
  }
  EXPECT_EQ(queue.peakSize(), 1000u);
  EXPECT_TRUE(queue.empty());
}

TEST(DistanceBucketQueue, ReleaseKeepsRoomForTheBoundAndFreesTheRest) {
  using Queue = DistanceBucketQueue<int>;
  Queue queue(100);
  // One entry in each of 101 buckets: a chunk each.
  for (uint32_t k = 0; k <= 100; ++k) queue.push(k, static_cast<int>(k));
  EXPECT_EQ(queue.capacity(), 101 * Queue::kChunkEntries);
  int entry = 0;
  uint32_t key = 0;
  while (!queue.empty()) queue.pop(&entry, &key);
  queue.releaseStorage(10 * Queue::kChunkEntries);
  EXPECT_EQ(queue.capacity(), 10 * Queue::kChunkEntries);
  queue.releaseStorage(0);
  EXPECT_EQ(queue.capacity(), 0u);
  queue.push(4, 1);  // still usable, from the lowest key again
  queue.push(2, 2);
  queue.pop(&entry, &key);
  EXPECT_EQ(key, 2u);
  EXPECT_EQ(entry, 2);
  // A moved-from queue is empty and a moved-to one keeps the entries.
  Queue moved = std::move(queue);
  EXPECT_EQ(moved.size(), 1u);
  moved.pop(&entry, &key);
  EXPECT_EQ(key, 4u);
  EXPECT_EQ(entry, 1);
}

}  // namespace
}  // namespace cblox
