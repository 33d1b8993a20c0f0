// FusionScheduler::exportState / restoreState: what a resumed mapper restores of its map
// maintenance (the keyframes' covisibility landmark sets, the back-off of rejected pairs).

#include <cmath>
#include <limits>
#include <vector>

#include <gtest/gtest.h>

#include "core/maintenance/fusion_scheduler.h"
#include "core/maintenance/fusion_scheduler_state.h"

namespace cblox {
namespace {

std::vector<uint64_t> range(uint64_t begin, uint64_t end) {
  std::vector<uint64_t> ids;
  for (uint64_t i = begin; i < end; ++i) ids.push_back(i);
  return ids;
}

FusionSchedulerConfig testConfig() {
  FusionSchedulerConfig config;
  config.candidates.min_shared_landmarks = 30;
  config.candidates.min_shared_ratio = 0.3;
  config.q_min = 100.0;
  config.retry_after_s = 4.0;
  config.max_retry_after_s = 64.0;
  return config;
}

void addThree(FusionScheduler* s) {
  s->addSubvolume(0, 10);
  s->addSubvolume(1, 20);
  s->addSubvolume(2, 30);
}

// Subvolumes 0, 1, 2: (0, 1) share 60 landmarks, (1, 2) 40, (0, 2) 5. At t = 0, (0, 1) is
// rejected by q (waits 4 s, one rejection) and (1, 2) answered with an error (waits 4 s).
FusionScheduler withHistory() {
  FusionScheduler s(testConfig());
  addThree(&s);
  s.addKeyframeLandmarks(0, 10, range(0, 100));
  s.addKeyframeLandmarks(1, 20, range(40, 140));
  s.addKeyframeLandmarks(2, 31, range(100, 200));
  s.addKeyframeLandmarks(2, 30, std::vector<uint64_t>{1u << 20, 3, 1, 2, 4, 0, uint64_t{1} << 63});
  const auto first = s.nextRequest(-1, 0.0);
  EXPECT_TRUE(first && first->pairs.size() == 1 && first->pairs[0].newer == 1);
  const FusionCovarianceAnswer low{true, "", 1.0};
  EXPECT_TRUE(s.onReply(first->request_id, std::vector{low}, 0.0).empty());
  const auto second = s.nextRequest(-1, 0.0);
  EXPECT_TRUE(second && second->pairs.size() == 1 && second->pairs[0].older == 1);
  const FusionCovarianceAnswer error{false, "singular", 0.0};
  EXPECT_TRUE(s.onReply(second->request_id, std::vector{error}, 0.0).empty());
  return s;
}

TEST(FusionSchedulerStateTest, ExportHoldsSortedLandmarkSetsAndBackoffs) {
  const FusionScheduler s = withHistory();
  const FusionSchedulerState state = s.exportState(1.0);
  EXPECT_EQ(state.validate(), "");
  ASSERT_EQ(state.subvolumes.size(), 3u);
  EXPECT_EQ(state.subvolumes[0].subvolume, 0);
  EXPECT_EQ(state.subvolumes[0].keyframes, (std::vector<KeyframeLandmarks>{{10, range(0, 100)}}));
  EXPECT_EQ(state.subvolumes[1].keyframes, (std::vector<KeyframeLandmarks>{{20, range(40, 140)}}));
  // Keyframes ascending, each set sorted.
  std::vector<uint64_t> first = range(0, 5);
  first.push_back(1u << 20);
  first.push_back(uint64_t{1} << 63);
  EXPECT_EQ(state.subvolumes[2].keyframes,
            (std::vector<KeyframeLandmarks>{{30, first}, {31, range(100, 200)}}));
  ASSERT_EQ(state.backoffs.size(), 2u);
  EXPECT_EQ(state.backoffs[0], (FusionPairBackoff{0, 1, 1, 3.0}));
  EXPECT_EQ(state.backoffs[1], (FusionPairBackoff{1, 2, 0, 3.0}));
  // Once the wait is over only the rejection count is left to remember.
  const FusionSchedulerState later = s.exportState(10.0);
  ASSERT_EQ(later.backoffs.size(), 1u);
  EXPECT_EQ(later.backoffs[0], (FusionPairBackoff{0, 1, 1, 0.0}));
}

TEST(FusionSchedulerStateTest, RestoreRebuildsTheSameGraphAndWaitsOnAnotherClock) {
  const FusionScheduler original = withHistory();
  const FusionSchedulerState state = original.exportState(1.0);

  FusionScheduler resumed(testConfig());
  addThree(&resumed);
  EXPECT_EQ(resumed.restoreState(state, 100.0), 0u);  // another process's clock
  EXPECT_EQ(resumed.exportState(100.0), state);
  for (int64_t a = 0; a < 3; ++a) {
    EXPECT_EQ(resumed.graph().numLandmarks(a), original.graph().numLandmarks(a));
    for (int64_t b = 0; b < 3; ++b)
      EXPECT_EQ(resumed.graph().weight(a, b), original.graph().weight(a, b));
  }
  EXPECT_EQ(resumed.graph().numEdges(), original.graph().numEdges());

  // Both pairs still wait their 3 s, on the new clock.
  EXPECT_FALSE(resumed.nextRequest(-1, 102.5).has_value());
  const auto request = resumed.nextRequest(-1, 103.0);
  ASSERT_TRUE(request.has_value());
  ASSERT_EQ(request->pairs.size(), 1u);
  EXPECT_EQ(request->pairs[0].older, 0);
  EXPECT_EQ(request->pairs[0].newer, 1);
  // The rejection count came along: a second rejection by q waits twice retry_after_s.
  const FusionCovarianceAnswer low{true, "", 1.0};
  EXPECT_TRUE(resumed.onReply(request->request_id, std::vector{low}, 103.0).empty());
  const FusionSchedulerState after = resumed.exportState(103.0);
  ASSERT_FALSE(after.backoffs.empty());
  EXPECT_EQ(after.backoffs[0], (FusionPairBackoff{0, 1, 2, 8.0}));
}

TEST(FusionSchedulerStateTest, EntriesOfUnknownSubvolumesAreIgnoredAndCounted) {
  FusionSchedulerState state;
  state.subvolumes = {{0, {{10, {1, 2, 3}}}}, {7, {{70, {1, 2}}}}};
  state.backoffs = {{0, 7, 2, 1.0}, {1, 2, 1, 0.0}};
  FusionScheduler s(testConfig());
  addThree(&s);
  EXPECT_EQ(s.restoreState(state, 0.0), 2u);
  const FusionSchedulerState restored = s.exportState(0.0);
  ASSERT_EQ(restored.subvolumes.size(), 3u);  // 0 with its landmarks, 1 and 2 empty
  EXPECT_EQ(restored.subvolumes[0], (SubvolumeLandmarks{0, {{10, {1, 2, 3}}}}));
  EXPECT_TRUE(restored.subvolumes[1].keyframes.empty());
  ASSERT_EQ(restored.backoffs.size(), 1u);
  EXPECT_EQ(restored.backoffs[0], (FusionPairBackoff{1, 2, 1, 0.0}));
}

TEST(FusionSchedulerStateTest, ValidateNamesWhatIsWrong) {
  const auto message = [](const FusionSchedulerState& s) { return s.validate(); };
  EXPECT_EQ(message({}), "");
  EXPECT_NE(message({{{1, {}}, {1, {}}}, {}}).find("subvolume ids do not strictly increase"),
            std::string::npos);
  EXPECT_NE(message({{{1, {{3, {5, 5}}}}}, {}}).find("keyframe 3: landmark ids do not strictly"),
            std::string::npos);
  EXPECT_NE(message({{{1, {{3, {}}, {3, {}}}}}, {}}).find("keyframe ids do not strictly increase"),
            std::string::npos);
  EXPECT_NE(message({{{1, {{-7, {}}}}}, {}}).find("keyframe -7: keyframe id is negative"),
            std::string::npos);
  EXPECT_EQ(message({{{1, {{KeyframeLandmarks::kUnknownKeyframe, {1}}, {0, {1}}}}}, {}}), "");
  EXPECT_NE(message({{}, {{2, 1, 0, 0.0}}}).find("older is not below newer"), std::string::npos);
  EXPECT_NE(message({{}, {{1, 3, 0, 1.0}, {1, 2, 0, 1.0}}}).find("pairs do not strictly increase"),
            std::string::npos);
  EXPECT_NE(message({{}, {{1, 2, -1, 0.0}}}).find("negative rejection count"), std::string::npos);
  EXPECT_NE(message({{}, {{1, 2, 0, std::numeric_limits<double>::quiet_NaN()}}}).find("retry_in_s"),
            std::string::npos);
  EXPECT_NE(message({{}, {{1, 2, 0, -1.0}}}).find("retry_in_s"), std::string::npos);
}

}  // namespace
}  // namespace cblox
