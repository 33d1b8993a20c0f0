#include "drivers/camera/timestamp_mapping.h"

#include <time.h>

#include <vector>

#include <gtest/gtest.h>

namespace cblox {
namespace {

TEST(TimestampMappingTest, TimevalToNsIsExact) {
  EXPECT_EQ(timevalToNs(timeval{0, 0}), 0);
  EXPECT_EQ(timevalToNs(timeval{12, 345678}), 12'345'678'000);
  EXPECT_EQ(timevalToNs(timeval{1'700'000'000, 999'999}), 1'700'000'000'999'999'000);
}

TEST(TimestampMappingTest, OffsetFromOneSampleIsTheBracketMidpoint) {
  const std::vector<ClockSample> samples = {{1'000'000'100, 500, 1'000'000'300}};
  const std::optional<ClockOffset> offset = estimateClockOffset(samples);
  ASSERT_TRUE(offset);
  EXPECT_EQ(offset->offset_ns, 1'000'000'200 - 500);
  EXPECT_EQ(offset->uncertainty_ns, 100);
  EXPECT_EQ(offset->monotonic_ns, 500);
}

TEST(TimestampMappingTest, TightestBracketWins) {
  // True offset 1e9; the loose samples' midpoints are off by +-40 ns, the tight one exact.
  const std::vector<ClockSample> samples = {
      {1'000'001'000, 1'000, 1'000'001'080},  // width 80, midpoint +40
      {1'000'002'010, 2'000, 1'000'002'030},  // width 20, midpoint +20... not tightest
      {1'000'002'995, 3'000, 1'000'003'005},  // width 10, midpoint exact
      {1'000'003'900, 4'000, 1'000'004'020},  // width 120, midpoint -40
  };
  const std::optional<ClockOffset> offset = estimateClockOffset(samples);
  ASSERT_TRUE(offset);
  EXPECT_EQ(offset->offset_ns, 1'000'000'000);
  EXPECT_EQ(offset->uncertainty_ns, 5);
  EXPECT_EQ(offset->monotonic_ns, 3'000);
}

TEST(TimestampMappingTest, BackwardsBracketsAreIgnored) {
  // The realtime clock stepped back during the first sample.
  const std::vector<ClockSample> samples = {{5'000, 100, 4'000}, {6'000, 200, 6'100}};
  const std::optional<ClockOffset> offset = estimateClockOffset(samples);
  ASSERT_TRUE(offset);
  EXPECT_EQ(offset->offset_ns, 6'050 - 200);
  EXPECT_FALSE(estimateClockOffset(std::vector<ClockSample>{{5'000, 100, 4'000}}));
  EXPECT_FALSE(estimateClockOffset(std::vector<ClockSample>{}));
}

TEST(TimestampMappingTest, MappingReestimatesAfterTheRefreshInterval) {
  // A fake pair of clocks: monotonic advances 1000 ns per sample, realtime = monotonic +
  // offset, with a 10 ns bracket; the offset changes (an NTP step) halfway.
  int64_t monotonic = 0;
  int64_t offset = 1'000'000'000;
  int calls = 0;
  auto sampler = [&] {
    ++calls;
    monotonic += 1'000;
    return ClockSample{monotonic + offset - 5, monotonic, monotonic + offset + 5};
  };
  ClockMappingOptions options;
  options.samples_per_estimate = 3;
  options.refresh_interval_ns = 1'000'000;
  MonotonicClockMapping mapping(options, sampler);
  EXPECT_EQ(mapping.toRealtimeNs(10'000), 10'000 + 1'000'000'000);
  EXPECT_EQ(calls, 3);
  EXPECT_EQ(mapping.toRealtimeNs(500'000), 500'000 + 1'000'000'000);  // not stale yet
  EXPECT_EQ(calls, 3);
  offset = 2'000'000'000;
  EXPECT_EQ(mapping.toRealtimeNs(1'200'000), 1'200'000 + 2'000'000'000);  // refreshed
  EXPECT_EQ(calls, 6);
  ASSERT_TRUE(mapping.offset());
  EXPECT_EQ(mapping.offset()->offset_ns, 2'000'000'000);
}

TEST(TimestampMappingTest, FailedEstimateKeepsThePreviousOffset) {
  bool broken = false;
  auto sampler = [&] { return broken ? ClockSample{10, 0, 5} : ClockSample{1'000, 100, 1'010}; };
  ClockMappingOptions options;
  options.refresh_interval_ns = 0;
  MonotonicClockMapping mapping(options, sampler);
  EXPECT_EQ(mapping.toRealtimeNs(100), 1'005);
  broken = true;
  EXPECT_FALSE(mapping.refresh());
  EXPECT_EQ(mapping.toRealtimeNs(100), 1'005);
}

TEST(TimestampMappingTest, SystemClocksGiveAPlausibleOffset) {
  MonotonicClockMapping mapping;
  timespec mono{}, real{};
  clock_gettime(CLOCK_MONOTONIC, &mono);
  clock_gettime(CLOCK_REALTIME, &real);
  const int64_t mapped = mapping.toRealtimeNs(mono.tv_sec * 1'000'000'000LL + mono.tv_nsec);
  const int64_t realtime = real.tv_sec * 1'000'000'000LL + real.tv_nsec;
  EXPECT_NEAR(static_cast<double>(mapped - realtime), 0.0, 5e6);  // within 5 ms
  ASSERT_TRUE(mapping.offset());
  EXPECT_LT(mapping.offset()->uncertainty_ns, 1'000'000);
}

}  // namespace
}  // namespace cblox
