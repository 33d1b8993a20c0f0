#include "core/integrator/approx_hash_set.h"

#include <atomic>
#include <cstdint>
#include <thread>
#include <vector>

#include <gtest/gtest.h>

namespace cblox {
namespace {

TEST(ApproxHashSet, InsertReportsNewKeysOnce) {
  ApproxHashSet set(16);
  EXPECT_EQ(set.numBuckets(), 65536u);
  EXPECT_TRUE(set.insert(42));
  EXPECT_FALSE(set.insert(42));
  EXPECT_TRUE(set.insert(43));
  EXPECT_FALSE(set.insert(43));
  EXPECT_TRUE(set.insert(0));  // key 0 is a valid key, not "empty"
  EXPECT_FALSE(set.insert(0));
}

TEST(ApproxHashSet, ContainsSeesInsertedKeysUntilClear) {
  ApproxHashSet set(16);
  EXPECT_FALSE(set.contains(0));  // a never-written bucket holds no key, not key 0
  EXPECT_FALSE(set.contains(42));
  EXPECT_TRUE(set.insert(42));
  EXPECT_TRUE(set.contains(42));
  EXPECT_FALSE(set.contains(43));
  EXPECT_TRUE(set.insert(0));
  EXPECT_TRUE(set.contains(0));
  set.clear();
  EXPECT_FALSE(set.contains(42));
  EXPECT_FALSE(set.contains(0));
  EXPECT_TRUE(set.insert(42));  // contains() did not insert
}

TEST(ApproxHashSet, ClearForgetsEverythingAndSurvivesEpochWrap) {
  ApproxHashSet set(16);
  for (int round = 0; round < 70000; ++round) {  // > 2^16 clears: the epoch wraps
    ASSERT_TRUE(set.insert(7)) << "round " << round;
    ASSERT_FALSE(set.insert(7));
    set.clear();
  }
}

TEST(ApproxHashSet, NeverReportsAKeyThatWasNotInserted) {
  // With >= 2^16 buckets bucket + fingerprint hold the whole bijective hash, so the
  // first insert of every distinct key must succeed even when buckets collide.
  ApproxHashSet set(16);
  for (uint64_t key = 0; key < 200000; ++key) ASSERT_TRUE(set.insert(key * 977 + 3)) << key;
}

TEST(ApproxHashSet, ConcurrentInsertsOfTheSameKeysSucceedAtLeastOncePerKey) {
  // Four threads insert the same keys at the same time. The CAS makes each bucket
  // transition happen once, so a key succeeds once, plus rarely again after an eviction
  // by a colliding key (with 2^24 buckets and 5e4 keys about 75 colliding pairs).
  ApproxHashSet set(24);
  constexpr uint64_t kKeys = 50000;
  std::vector<std::atomic<int>> successes(kKeys);
  std::vector<std::thread> threads;
  for (int t = 0; t < 4; ++t) {
    threads.emplace_back([&] {
      for (uint64_t key = 0; key < kKeys; ++key) {
        if (set.insert(key)) successes[key].fetch_add(1);
      }
    });
  }
  for (auto& thread : threads) thread.join();
  uint64_t total = 0;
  for (uint64_t key = 0; key < kKeys; ++key) {
    ASSERT_GE(successes[key].load(), 1) << key;
    total += static_cast<uint64_t>(successes[key].load());
  }
  EXPECT_LE(total, kKeys + 1000);
}

}  // namespace
}  // namespace cblox
