#include "drivers/camera/stereo_pairer.h"

#include <stdexcept>
#include <vector>

#include <gtest/gtest.h>

namespace cblox {
namespace {

constexpr int64_t kMs = 1'000'000;
constexpr int64_t kPeriod = 33 * kMs;  // ~30 Hz

/// Feeds frames and collects what the pairer decides.
struct Harness {
  explicit Harness(StereoPairerOptions options) : pairer(options) {}

  void left(int64_t t, uint64_t id) { pairer.push(StereoSide::kLeft, t, id, &pairs, &drops); }
  void right(int64_t t, uint64_t id) { pairer.push(StereoSide::kRight, t, id, &pairs, &drops); }

  StereoPairer pairer;
  std::vector<StereoPair> pairs;
  std::vector<StereoDrop> drops;
};

StereoPairerOptions options(int64_t tolerance_ns) {
  StereoPairerOptions o;
  o.tolerance_ns = tolerance_ns;
  o.max_wait_ns = 200 * kMs;
  o.max_queue = 8;
  return o;
}

TEST(StereoPairerTest, OptionsAreValidated) {
  StereoPairerOptions bad = options(0);
  EXPECT_EQ(bad.validate(), "tolerance_ns must be > 0, got 0");
  EXPECT_THROW(StereoPairer{bad}, std::invalid_argument);
  bad = options(5 * kMs);
  bad.max_wait_ns = kMs;
  EXPECT_NE(bad.validate(), "");
  bad = options(5 * kMs);
  bad.max_queue = 0;
  EXPECT_NE(bad.validate(), "");
  EXPECT_EQ(options(5 * kMs).validate(), "");
}

TEST(StereoPairerTest, SynchronisedStreamsPairExactly) {
  Harness h(options(5 * kMs));
  for (uint64_t i = 0; i < 10; ++i) {
    h.left(static_cast<int64_t>(i) * kPeriod, i);
    h.right(static_cast<int64_t>(i) * kPeriod, 100 + i);
  }
  ASSERT_EQ(h.pairs.size(), 10u);
  for (uint64_t i = 0; i < 10; ++i) {
    EXPECT_EQ(h.pairs[i].left_id, i);
    EXPECT_EQ(h.pairs[i].right_id, 100 + i);
  }
  EXPECT_TRUE(h.drops.empty());
  EXPECT_EQ(h.pairer.stats().pairs, 10);
  EXPECT_EQ(h.pairer.stats().max_abs_dt_ns, 0);
}

TEST(StereoPairerTest, JitterWithinTolerancePairsAndRecordsDt) {
  Harness h(options(5 * kMs));
  const int64_t jitter[] = {0, 3 * kMs, -4 * kMs, 1 * kMs, -2 * kMs, 5 * kMs};
  for (uint64_t i = 0; i < 6; ++i) {
    const int64_t t = static_cast<int64_t>(i) * kPeriod;
    // Arrival order alternates between the streams.
    if (i % 2 == 0) {
      h.left(t, i);
      h.right(t + jitter[i], 100 + i);
    } else {
      h.right(t + jitter[i], 100 + i);
      h.left(t, i);
    }
  }
  ASSERT_EQ(h.pairs.size(), 6u);
  for (uint64_t i = 0; i < 6; ++i) {
    EXPECT_EQ(h.pairs[i].left_id, i);
    EXPECT_EQ(h.pairs[i].right_id, 100 + i);
    EXPECT_EQ(h.pairs[i].right_ns - h.pairs[i].left_ns, jitter[i]);
  }
  EXPECT_EQ(h.pairer.stats().last_dt_ns, 5 * kMs);
  EXPECT_EQ(h.pairer.stats().max_abs_dt_ns, 5 * kMs);
  EXPECT_TRUE(h.drops.empty());
}

TEST(StereoPairerTest, FrameLostOnOneSideDropsItsPartnerWithoutDrift) {
  Harness h(options(5 * kMs));
  for (uint64_t i = 0; i < 8; ++i) {
    const int64_t t = static_cast<int64_t>(i) * kPeriod;
    h.left(t, i);
    if (i != 4) h.right(t + kMs, 100 + i);  // the right camera lost frame 4
  }
  ASSERT_EQ(h.pairs.size(), 7u);
  ASSERT_EQ(h.drops.size(), 1u);
  EXPECT_EQ(h.drops[0].side, StereoSide::kLeft);
  EXPECT_EQ(h.drops[0].id, 4u);
  EXPECT_EQ(h.drops[0].reason, StereoDropReason::kUnpaired);
  EXPECT_EQ(h.pairer.stats().left_unpaired, 1);
  EXPECT_EQ(h.pairer.stats().right_unpaired, 0);
  EXPECT_EQ(h.pairer.stats().drift, 0);
  EXPECT_EQ(h.pairs[4].left_id, 5u);
  EXPECT_EQ(h.pairs[4].right_id, 105u);
}

TEST(StereoPairerTest, StreamsDriftingApartStopPairingAndCountDrift) {
  // The right camera runs 1 ms per frame slow: dt = i ms. With a 5 ms tolerance, frames
  // 0..5 pair, then every frame is unpaired on both sides, counted as drift (the other
  // stream's nearest frame is closer than half a frame interval).
  Harness h(options(5 * kMs));
  for (uint64_t i = 0; i < 12; ++i) {
    const int64_t t = static_cast<int64_t>(i) * kPeriod;
    h.left(t, i);
    h.right(t + static_cast<int64_t>(i) * kMs, 100 + i);
  }
  EXPECT_EQ(h.pairer.stats().pairs, 6);
  for (size_t i = 0; i < h.pairs.size(); ++i) EXPECT_EQ(h.pairs[i].left_id, i);
  // Lefts 6..10 are decided (unpaired) once the next right has arrived; right 6..10 too.
  EXPECT_EQ(h.pairer.stats().left_unpaired, 6);
  EXPECT_EQ(h.pairer.stats().right_unpaired, 5);
  EXPECT_EQ(h.pairer.stats().drift, 11);
  EXPECT_EQ(h.pairer.stats().max_abs_dt_ns, 5 * kMs);
}

TEST(StereoPairerTest, NearestFrameWinsWhenTwoAreWithinTolerance) {
  // A tolerance wider than half the interval: right 1 (t = 10) is nearer to left 1 (t = 9)
  // than right 0 (t = 2) is.
  Harness h(options(8 * kMs));
  h.right(2 * kMs, 100);
  h.right(10 * kMs, 101);
  h.left(9 * kMs, 1);
  ASSERT_EQ(h.pairs.size(), 1u);
  EXPECT_EQ(h.pairs[0].left_id, 1u);
  EXPECT_EQ(h.pairs[0].right_id, 101u);
  ASSERT_EQ(h.drops.size(), 1u);
  EXPECT_EQ(h.drops[0].id, 100u);
  EXPECT_EQ(h.drops[0].side, StereoSide::kRight);
}

TEST(StereoPairerTest, OutOfOrderFramesAreSortedOrDropped) {
  Harness h(options(5 * kMs));
  // Left frames 1 and 0 arrive swapped before any right frame: sorted, both pair.
  h.left(kPeriod, 1);
  h.left(0, 0);
  h.right(0, 100);
  h.right(kPeriod, 101);
  ASSERT_EQ(h.pairs.size(), 2u);
  EXPECT_EQ(h.pairs[0].left_id, 0u);
  EXPECT_EQ(h.pairs[1].left_id, 1u);
  // A left frame older than one already paired: dropped as out of order.
  h.left(kPeriod / 2, 2);
  ASSERT_EQ(h.drops.size(), 1u);
  EXPECT_EQ(h.drops[0].reason, StereoDropReason::kOutOfOrder);
  EXPECT_EQ(h.drops[0].id, 2u);
  // A duplicate timestamp of a waiting frame too.
  h.left(2 * kPeriod, 3);
  h.left(2 * kPeriod, 4);
  ASSERT_EQ(h.drops.size(), 2u);
  EXPECT_EQ(h.drops[1].id, 4u);
  EXPECT_EQ(h.pairer.stats().out_of_order, 2);
  EXPECT_EQ(h.pairer.stats().left_unpaired, 0);
  h.right(2 * kPeriod, 102);
  EXPECT_EQ(h.pairs.back().left_id, 3u);
}

TEST(StereoPairerTest, SilentStreamBoundsTheWait) {
  StereoPairerOptions o = options(5 * kMs);
  o.max_wait_ns = 100 * kMs;
  o.max_queue = 3;
  Harness h(o);
  // The right camera delivers nothing: lefts expire 100 ms behind the newest; with frames
  // 33 ms apart at most 4 would wait, the queue bound of 3 drops the oldest first.
  for (uint64_t i = 0; i < 10; ++i) h.left(static_cast<int64_t>(i) * kPeriod, i);
  EXPECT_EQ(h.pairer.waiting(StereoSide::kLeft), 3u);
  EXPECT_EQ(h.pairer.stats().left_unpaired, 7);
  EXPECT_EQ(h.pairer.stats().overflow, 7);
  EXPECT_EQ(h.pairer.stats().drift, 0);

  o.max_queue = 8;
  Harness expiring(o);
  for (uint64_t i = 0; i < 10; ++i) expiring.left(static_cast<int64_t>(i) * kPeriod, i);
  // Newest 297 ms: frames before 197 ms (0..5) expired; 6..9 wait.
  EXPECT_EQ(expiring.pairer.waiting(StereoSide::kLeft), 4u);
  EXPECT_EQ(expiring.pairer.stats().left_unpaired, 6);
  for (const StereoDrop& d : expiring.drops) EXPECT_EQ(d.reason, StereoDropReason::kExpired);
  // The right stream comes back in step: pairs resume.
  expiring.right(9 * kPeriod, 109);
  ASSERT_EQ(expiring.pairs.size(), 1u);
  EXPECT_EQ(expiring.pairs[0].left_id, 9u);
  EXPECT_EQ(expiring.pairer.stats().left_unpaired, 9);  // 6, 7, 8 could have no partner
}

TEST(StereoPairerTest, ClearFlushesWithoutCounting) {
  Harness h(options(5 * kMs));
  h.left(0, 0);
  h.left(kPeriod, 1);
  std::vector<StereoDrop> flushed;
  h.pairer.clear(&flushed);
  ASSERT_EQ(flushed.size(), 2u);
  EXPECT_EQ(flushed[0].reason, StereoDropReason::kFlushed);
  EXPECT_EQ(h.pairer.stats().left_unpaired, 0);
  EXPECT_EQ(h.pairer.waiting(StereoSide::kLeft), 0u);
  // History forgotten: an earlier timestamp is accepted again (the cameras restarted).
  h.left(0, 2);
  h.right(0, 102);
  ASSERT_EQ(h.pairs.size(), 1u);
  EXPECT_EQ(h.pairs[0].left_id, 2u);
}

}  // namespace
}  // namespace cblox
