#include "core/maintenance/fusion_scheduler.h"

#include <stdexcept>
#include <tuple>
#include <vector>

#include <gtest/gtest.h>

#include "test/test_support/enum_names.h"

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
  config.reply_timeout_s = 2.0;
  config.retry_after_s = 5.0;
  return config;
}

FusionCovarianceAnswer answer(double q) { return FusionCovarianceAnswer{true, "", q}; }

// Subvolumes 0, 1, 2 anchored at keyframes 10, 20, 30 (2 also holds keyframe 31): 0 and 1
// share 60 of 100 landmarks, 1 and 2 share 40, 0 and 2 share 5 (below both bounds).
FusionScheduler threeSubvolumes(const FusionSchedulerConfig& config = testConfig()) {
  FusionScheduler s(config);
  s.addSubvolume(0, 10);
  s.addSubvolume(1, 20);
  s.addSubvolume(2, 30);
  s.addKeyframeLandmarks(0, 10, range(0, 100));
  s.addKeyframeLandmarks(1, 20, range(40, 140));
  s.addKeyframeLandmarks(2, 30, range(100, 200));
  s.addKeyframeLandmarks(2, 31, range(0, 5));
  return s;
}

TEST(FusionSchedulerTest, RequestsTheStrongestPairsWithTheirAnchorKeyframes) {
  FusionScheduler s = threeSubvolumes();
  ASSERT_EQ(s.graph().weight(0, 1), 60);
  ASSERT_EQ(s.graph().weight(1, 2), 40);
  ASSERT_EQ(s.graph().weight(0, 2), 5);
  // Subvolume 1 can be in one pair only: (0, 1) is stronger, so (1, 2) waits.
  const auto request = s.nextRequest(/*active_subvolume=*/-1, 0.0);
  ASSERT_TRUE(request.has_value());
  EXPECT_EQ(request->request_id, 1);
  ASSERT_EQ(request->pairs.size(), 1u);
  const FusionPair& p = request->pairs[0];
  EXPECT_EQ(p.older, 0);
  EXPECT_EQ(p.newer, 1);
  EXPECT_EQ(p.older_keyframe, 10);
  EXPECT_EQ(p.newer_keyframe, 20);
  EXPECT_EQ(p.shared_landmarks, 60);
  EXPECT_EQ(s.stats().candidates, 1u);
  EXPECT_EQ(s.stats().requested, 1u);
}

TEST(FusionSchedulerTest, TheActiveSubvolumeIsNeverProposed) {
  FusionScheduler s = threeSubvolumes();
  const auto request = s.nextRequest(/*active_subvolume=*/0, 0.0);
  ASSERT_TRUE(request.has_value());
  ASSERT_EQ(request->pairs.size(), 1u);
  EXPECT_EQ(request->pairs[0].older, 1);
  EXPECT_EQ(request->pairs[0].newer, 2);
  FusionScheduler only_active_pairs = threeSubvolumes();
  EXPECT_FALSE(only_active_pairs.nextRequest(/*active_subvolume=*/1, 0.0).has_value());
}

// A revisit subvolume shares its home's anchor and the anchor's landmarks; pairs sharing an
// anchor are handed over for fusion without a covariance (the two oldest per anchor, the
// active one excluded, each pair locked until fused), and never requested.
TEST(FusionSchedulerTest, SubvolumesSharingAnAnchorAreFusedWithoutACovariance) {
  FusionScheduler s = threeSubvolumes();
  EXPECT_FALSE(s.addSubvolumeSharingAnchor(4, 99));  // unknown home
  ASSERT_TRUE(s.addSubvolumeSharingAnchor(3, 0));    // anchored at 10 with 0's landmarks
  ASSERT_TRUE(s.addSubvolumeSharingAnchor(4, 0));
  ASSERT_TRUE(s.addSubvolumeSharingAnchor(5, 1));  // anchored at 20
  EXPECT_EQ(s.graph().weight(0, 3), 100);
  EXPECT_EQ(s.graph().weight(3, 4), 100);
  EXPECT_EQ(s.graph().weight(1, 5), 100);
  EXPECT_EQ(std::get<2>(s.mostSharedKeyframes(0, 3)), 100);

  // 5 is active: anchor 20 has no free pair. Anchor 10: (0, 3); 4 waits for the next call.
  std::vector<FusionPair> pairs = s.takeSameAnchorPairs(/*active_subvolume=*/5);
  ASSERT_EQ(pairs.size(), 1u);
  EXPECT_EQ(pairs[0].older, 0);
  EXPECT_EQ(pairs[0].newer, 3);
  EXPECT_EQ(pairs[0].older_keyframe, 10);
  EXPECT_EQ(pairs[0].newer_keyframe, 10);
  EXPECT_EQ(pairs[0].shared_landmarks, 100);
  EXPECT_EQ(s.fusionsInProgress(), 1u);
  EXPECT_TRUE(s.takeSameAnchorPairs(5).empty());  // 0 is locked; 4 has no partner
  // With 0 and 3 locked and 5 active, the strongest free edge is (1, 4): 60 landmarks.
  const auto request = s.nextRequest(5, 0.0);
  ASSERT_TRUE(request.has_value());
  ASSERT_EQ(request->pairs.size(), 1u);
  EXPECT_EQ(request->pairs[0].older, 1);
  EXPECT_EQ(request->pairs[0].newer, 4);
  s.onFused(pairs[0]);
  EXPECT_EQ(s.stats().same_anchor, 1u);
  EXPECT_EQ(s.stats().accepted, 0u);
  EXPECT_EQ(s.stats().fused, 1u);
  // Now 0 and 4 pair, and 1 and 5 once 5 is no longer active (a request does not lock).
  pairs = s.takeSameAnchorPairs(-1);
  ASSERT_EQ(pairs.size(), 2u);
  EXPECT_EQ(std::tie(pairs[0].older, pairs[0].newer), std::make_tuple(0, 4));
  EXPECT_EQ(std::tie(pairs[1].older, pairs[1].newer), std::make_tuple(1, 5));
  EXPECT_EQ(pairs[1].older_keyframe, 20);
  EXPECT_EQ(s.stats().same_anchor, 3u);
  // Same-anchor pairs are never in a covariance request, even when nothing else is left.
  FusionScheduler only = threeSubvolumes();
  ASSERT_TRUE(only.addSubvolumeSharingAnchor(3, 0));
  only.onReply(only.nextRequest(-1, 0.0)->request_id, std::vector{answer(1.0)}, 0.0);  // (0, 1)
  while (const auto r = only.nextRequest(-1, 100.0)) {
    for (const FusionPair& p : r->pairs) EXPECT_NE(p.older_keyframe, p.newer_keyframe);
    only.onReply(r->request_id, std::vector<FusionCovarianceAnswer>(r->pairs.size(), answer(1.0)),
                 100.0);
  }
}

// A subvolume anchored at a keyframe whose subvolume was fused into an older one follows it
// there without a covariance, also after that one was fused further; such a pair is never
// requested.
TEST(FusionSchedulerTest, ASubvolumeFollowsItsAnchorsSubvolumeIntoWhatAbsorbedIt) {
  FusionScheduler s(testConfig());
  s.addSubvolume(0, 10);
  s.addSubvolume(1, 20);
  s.addSubvolume(2, 30);
  s.addKeyframeLandmarks(0, 10, range(0, 100));
  s.addKeyframeLandmarks(1, 20, range(50, 150));
  s.addKeyframeLandmarks(2, 30, range(100, 200));
  ASSERT_TRUE(s.addSubvolumeSharingAnchor(3, 2));  // a revisit of 2, anchored at 30
  // 0 active: (2, 3) shares an anchor and is not requested; (1, 2) is, and is fused.
  auto request = s.nextRequest(/*active_subvolume=*/0, 0.0);
  ASSERT_TRUE(request.has_value());
  ASSERT_EQ(request->pairs.size(), 1u);
  ASSERT_EQ(std::tie(request->pairs[0].older, request->pairs[0].newer), std::make_tuple(1, 2));
  std::vector<FusionPair> accepted = s.onReply(request->request_id, std::vector{answer(1e3)}, 0.0);
  ASSERT_EQ(accepted.size(), 1u);
  s.onFused(accepted[0]);
  // 3 active: (1, 3) would now go without a covariance, so only (0, 1) is requested.
  request = s.nextRequest(3, 1.0);
  ASSERT_TRUE(request.has_value());
  ASSERT_EQ(request->pairs.size(), 1u);
  ASSERT_EQ(std::tie(request->pairs[0].older, request->pairs[0].newer), std::make_tuple(0, 1));
  accepted = s.onReply(request->request_id, std::vector{answer(1e3)}, 1.0);
  ASSERT_EQ(accepted.size(), 1u);
  s.onFused(accepted[0]);
  EXPECT_TRUE(s.takeSameAnchorPairs(3).empty());  // still active
  const std::vector<FusionPair> pairs = s.takeSameAnchorPairs(-1);
  ASSERT_EQ(pairs.size(), 1u);
  EXPECT_EQ(pairs[0].older, 0);
  EXPECT_EQ(pairs[0].newer, 3);
  EXPECT_EQ(pairs[0].older_keyframe, 10);
  EXPECT_EQ(pairs[0].newer_keyframe, 30);
  EXPECT_EQ(s.stats().same_anchor, 1u);
  EXPECT_EQ(s.stats().accepted, 2u);
}

TEST(FusionSchedulerTest, SameAnchorPairsNeedFusionEnabled) {
  FusionSchedulerConfig config = testConfig();
  config.enabled = false;
  FusionScheduler s = threeSubvolumes(config);
  ASSERT_TRUE(s.addSubvolumeSharingAnchor(3, 0));
  EXPECT_TRUE(s.takeSameAnchorPairs(-1).empty());
  EXPECT_EQ(s.stats().same_anchor, 0u);
}

TEST(FusionSchedulerTest, OneRequestInFlightUntilItsReplyOrTimeout) {
  FusionScheduler s = threeSubvolumes();
  const auto first = s.nextRequest(-1, 0.0);
  ASSERT_TRUE(first.has_value());
  EXPECT_TRUE(s.requestInFlight());
  EXPECT_FALSE(s.nextRequest(-1, 1.9).has_value());
  // Timed out at 2 s: the same pair is asked again under a new id.
  const auto second = s.nextRequest(-1, 2.0);
  ASSERT_TRUE(second.has_value());
  EXPECT_EQ(second->request_id, 2);
  EXPECT_EQ(second->pairs[0].newer, 1);
  EXPECT_EQ(s.stats().requests_timed_out, 1u);
  EXPECT_EQ(s.stats().candidates, 1u);  // the same pair, counted once
  EXPECT_EQ(s.stats().requested, 2u);
  // The late reply to the first request is used: the pair is accepted; the second request
  // stays in flight, and its reply cannot fuse the locked pair again.
  const std::vector<FusionCovarianceAnswer> answers{answer(1e6)};
  const std::vector<FusionPair> fuse = s.onReply(first->request_id, answers, 2.5);
  ASSERT_EQ(fuse.size(), 1u);
  EXPECT_EQ(fuse[0].older, 0);
  EXPECT_EQ(fuse[0].newer, 1);
  EXPECT_EQ(s.stats().late_replies, 1u);
  EXPECT_EQ(s.stats().accepted, 1u);
  EXPECT_TRUE(s.requestInFlight());
  // The same reply again is a duplicate: ignored.
  EXPECT_TRUE(s.onReply(first->request_id, answers, 2.6).empty());
  EXPECT_EQ(s.stats().replies_ignored, 1u);
  EXPECT_TRUE(s.onReply(second->request_id, answers, 2.7).empty());
  EXPECT_FALSE(s.requestInFlight());
  EXPECT_EQ(s.stats().accepted, 1u);
  EXPECT_EQ(s.fusionsInProgress(), 1u);
}

// Only the last kKeptTimedOut timed-out requests are kept for late replies; a late answer
// below q_min is a rejection like a timely one.
TEST(FusionSchedulerTest, KeepsTheLastTimedOutRequestsForLateReplies) {
  FusionScheduler s = threeSubvolumes();
  std::vector<int64_t> ids;
  for (size_t k = 0; k <= FusionScheduler::kKeptTimedOut; ++k) {
    const auto r = s.nextRequest(-1, 2.0 * static_cast<double>(k));
    ASSERT_TRUE(r.has_value());
    ids.push_back(r->request_id);
  }
  ASSERT_TRUE(s.nextRequest(-1, 2.0 * static_cast<double>(ids.size())).has_value());
  EXPECT_EQ(s.stats().requests_timed_out, ids.size());
  const std::vector<FusionCovarianceAnswer> low{answer(1.0)};
  EXPECT_TRUE(s.onReply(ids[0], low, 20.0).empty());  // forgotten
  EXPECT_EQ(s.stats().replies_ignored, 1u);
  EXPECT_EQ(s.stats().rejected_by_q, 0u);
  EXPECT_TRUE(s.onReply(ids[1], low, 20.0).empty());  // kept: a rejection
  EXPECT_EQ(s.stats().late_replies, 1u);
  EXPECT_EQ(s.stats().rejected_by_q, 1u);
  EXPECT_TRUE(s.requestInFlight());
}

TEST(FusionSchedulerTest, AcceptsPairsAtOrAboveQMinAndLocksThemUntilFused) {
  FusionScheduler s = threeSubvolumes();
  const auto request = s.nextRequest(-1, 0.0);
  const std::vector<FusionCovarianceAnswer> answers{answer(100.0)};  // exactly q_min
  const std::vector<FusionPair> fuse = s.onReply(request->request_id, answers, 0.1);
  ASSERT_EQ(fuse.size(), 1u);
  EXPECT_EQ(fuse[0].older, 0);
  EXPECT_EQ(fuse[0].newer, 1);
  EXPECT_EQ(s.stats().accepted, 1u);
  EXPECT_EQ(s.fusionsInProgress(), 1u);
  // While 0 and 1 are being fused, no pair with either is proposed: (1, 2) waits.
  EXPECT_FALSE(s.nextRequest(-1, 0.2).has_value());
  s.onFused(fuse[0]);
  EXPECT_EQ(s.fusionsInProgress(), 0u);
  EXPECT_EQ(s.stats().fused, 1u);
  // 0 took 1's landmarks: L_0 = [0, 140), so W(0, 2) = |[100, 140)| + |[0, 5)| = 45.
  EXPECT_FALSE(s.graph().contains(1));
  EXPECT_EQ(s.graph().weight(0, 2), 45);
  const auto next = s.nextRequest(-1, 0.3);
  ASSERT_TRUE(next.has_value());
  ASSERT_EQ(next->pairs.size(), 1u);
  EXPECT_EQ(next->pairs[0].older, 0);
  EXPECT_EQ(next->pairs[0].newer, 2);
  EXPECT_EQ(next->pairs[0].shared_landmarks, 45);
  EXPECT_EQ(next->pairs[0].older_keyframe, 10);  // the anchors (the default)
  EXPECT_EQ(next->pairs[0].newer_keyframe, 30);
  EXPECT_EQ(next->pairs[0].keyframe_shared_landmarks, 0);
  // 0 also took 1's keyframe 20, which shares [100, 140) with 2's keyframe 30: the pair
  // most_shared would ask about.
  EXPECT_EQ(s.mostSharedKeyframes(0, 2), std::make_tuple(int64_t{20}, int64_t{30}, 40));
}

// Subvolume 0: keyframes 10 (anchor), 11, 12 along a corridor; subvolume 1 revisits it:
// keyframes 20 (anchor, far away), 21 (sees 12's landmarks), 22 (sees 11's, fewer of them).
FusionScheduler revisit(PairKeyframes choice, int revisit_keyframe_gap = 30) {
  FusionSchedulerConfig config = testConfig();
  config.pair_keyframes = choice;
  config.revisit_keyframe_gap = revisit_keyframe_gap;
  FusionScheduler s(config);
  s.addSubvolume(0, 10);
  s.addSubvolume(1, 20);
  s.addKeyframeLandmarks(0, 10, range(0, 50));
  s.addKeyframeLandmarks(0, 11, range(50, 100));
  s.addKeyframeLandmarks(0, 12, range(100, 150));
  s.addKeyframeLandmarks(1, 20, range(500, 540));
  s.addKeyframeLandmarks(1, 21, range(110, 150));
  s.addKeyframeLandmarks(1, 22, range(80, 100));
  return s;
}

TEST(FusionSchedulerTest, MostSharedAsksAboutTheKeyframesWhereTheSubvolumesOverlap) {
  FusionScheduler s = revisit(PairKeyframes::kMostShared);
  ASSERT_EQ(s.graph().weight(0, 1), 60);
  EXPECT_EQ(s.mostSharedKeyframes(0, 1), std::make_tuple(int64_t{12}, int64_t{21}, 40));
  const auto request = s.nextRequest(-1, 0.0);
  ASSERT_TRUE(request.has_value());
  ASSERT_EQ(request->pairs.size(), 1u);
  EXPECT_EQ(request->pairs[0].older_keyframe, 12);
  EXPECT_EQ(request->pairs[0].newer_keyframe, 21);
  EXPECT_EQ(request->pairs[0].keyframe_shared_landmarks, 40);
  EXPECT_EQ(request->pairs[0].shared_landmarks, 60);

  FusionScheduler anchors = revisit(PairKeyframes::kAnchors);
  const auto by_anchor = anchors.nextRequest(-1, 0.0);
  ASSERT_TRUE(by_anchor.has_value());
  EXPECT_EQ(by_anchor->pairs[0].older_keyframe, 10);
  EXPECT_EQ(by_anchor->pairs[0].newer_keyframe, 20);
  EXPECT_EQ(by_anchor->pairs[0].keyframe_shared_landmarks, 0);
}

TEST(FusionSchedulerTest, MostSharedOnRevisitsAsksAboutTheOverlapOnlyWhenSeenFarApartInTime) {
  // The overlap is keyframes 12 and 21: 9 ids apart.
  for (const int gap : {1, 9, 10, 30}) {
    SCOPED_TRACE(gap);
    FusionScheduler s = revisit(PairKeyframes::kMostSharedOnRevisits, gap);
    const auto request = s.nextRequest(-1, 0.0);
    ASSERT_TRUE(request.has_value());
    ASSERT_EQ(request->pairs.size(), 1u);
    EXPECT_EQ(request->pairs[0].shared_landmarks, 60);
    if (gap <= 9) {
      EXPECT_EQ(request->pairs[0].older_keyframe, 12);
      EXPECT_EQ(request->pairs[0].newer_keyframe, 21);
      EXPECT_EQ(request->pairs[0].keyframe_shared_landmarks, 40);
    } else {
      EXPECT_EQ(request->pairs[0].older_keyframe, 10);
      EXPECT_EQ(request->pairs[0].newer_keyframe, 20);
      EXPECT_EQ(request->pairs[0].keyframe_shared_landmarks, 0);
    }
  }
  // The gap is |newer - older| whichever subvolume holds the later keyframe: here the older
  // subvolume's keyframe 45 shares the most (100) with the newer's 23, 22 ids before it.
  for (const int gap : {22, 23}) {
    SCOPED_TRACE(gap);
    FusionScheduler later = revisit(PairKeyframes::kMostSharedOnRevisits, gap);
    later.addKeyframeLandmarks(0, 45, range(600, 700));
    later.addKeyframeLandmarks(1, 23, range(600, 700));
    const auto request = later.nextRequest(-1, 0.0);
    ASSERT_TRUE(request.has_value());
    EXPECT_EQ(request->pairs[0].older_keyframe, gap == 22 ? 45 : 10);
    EXPECT_EQ(request->pairs[0].newer_keyframe, gap == 22 ? 23 : 20);
  }
  FusionSchedulerConfig bad = testConfig();
  bad.pair_keyframes = PairKeyframes::kMostSharedOnRevisits;
  bad.revisit_keyframe_gap = 0;
  EXPECT_NE(bad.validate().find("revisit_keyframe_gap must be >= 1, got 0"), std::string::npos);
}

TEST(FusionSchedulerTest, MostSharedTiesGoToTheLowestIdsAndUnknownKeyframesAreNeverChosen) {
  FusionSchedulerConfig config = testConfig();
  config.pair_keyframes = PairKeyframes::kMostShared;
  FusionScheduler s(config);
  s.addSubvolume(0, 10);
  s.addSubvolume(1, 20);
  // Keyframes 11 and 12 of 0 each share 30 with 1's keyframes 21 and 22.
  s.addKeyframeLandmarks(0, 12, range(0, 30));
  s.addKeyframeLandmarks(0, 11, range(0, 30));
  s.addKeyframeLandmarks(1, 22, range(0, 30));
  s.addKeyframeLandmarks(1, 21, range(0, 30));
  EXPECT_EQ(s.mostSharedKeyframes(0, 1), std::make_tuple(int64_t{11}, int64_t{21}, 30));
  // A set whose keyframe is not known (read from a version 2 manifest) shares more, but a
  // covariance cannot be asked for it.
  constexpr int64_t kUnknown = KeyframeLandmarks::kUnknownKeyframe;
  s.addKeyframeLandmarks(0, kUnknown, range(0, 100));
  s.addKeyframeLandmarks(1, kUnknown, range(0, 100));
  EXPECT_EQ(s.mostSharedKeyframes(0, 1), std::make_tuple(int64_t{11}, int64_t{21}, 30));
  // Only sets of unknown keyframes share anything: the anchors.
  FusionScheduler old(config);
  old.addSubvolume(0, 10);
  old.addSubvolume(1, 20);
  old.addKeyframeLandmarks(0, kUnknown, range(0, 100));
  old.addKeyframeLandmarks(1, kUnknown, range(0, 100));
  old.addKeyframeLandmarks(1, 21, range(200, 300));
  EXPECT_EQ(old.mostSharedKeyframes(0, 1), std::make_tuple(int64_t{10}, int64_t{20}, 0));
  const auto request = old.nextRequest(-1, 0.0);
  ASSERT_TRUE(request.has_value());
  EXPECT_EQ(request->pairs[0].older_keyframe, 10);
  EXPECT_EQ(request->pairs[0].newer_keyframe, 20);
}

TEST(FusionSchedulerTest, PairKeyframesNamesRoundTrip) {
  test::expectNamesRoundTrip(
      {PairKeyframes::kAnchors, PairKeyframes::kMostShared, PairKeyframes::kMostSharedOnRevisits},
      pairKeyframesName, parsePairKeyframes, "nearest");
  FusionSchedulerConfig bad;
  bad.pair_keyframes = static_cast<PairKeyframes>(7);
  EXPECT_NE(bad.validate().find("pair_keyframes"), std::string::npos);
}

TEST(FusionSchedulerTest, RejectedAndFailedPairsWaitBeforeTheyAreAskedAgain) {
  FusionScheduler s = threeSubvolumes();
  const auto request = s.nextRequest(-1, 0.0);
  const std::vector<FusionCovarianceAnswer> low{answer(99.9)};
  EXPECT_TRUE(s.onReply(request->request_id, low, 1.0).empty());
  EXPECT_EQ(s.stats().rejected_by_q, 1u);
  // (0, 1) waits until 6 s; (1, 2) is free meanwhile.
  const auto meanwhile = s.nextRequest(-1, 1.0);
  ASSERT_TRUE(meanwhile.has_value());
  ASSERT_EQ(meanwhile->pairs.size(), 1u);
  EXPECT_EQ(meanwhile->pairs[0].older, 1);
  const std::vector<FusionCovarianceAnswer> error{FusionCovarianceAnswer{false, "stale", 0.0}};
  EXPECT_TRUE(s.onReply(meanwhile->request_id, error, 1.5).empty());
  EXPECT_EQ(s.stats().covariance_errors, 1u);
  EXPECT_FALSE(s.nextRequest(-1, 5.9).has_value());
  const auto again = s.nextRequest(-1, 6.0);
  ASSERT_TRUE(again.has_value());
  EXPECT_EQ(again->pairs[0].older, 0);
  EXPECT_EQ(again->pairs[0].newer, 1);
  // The fusion itself fails (e.g. a subvolume vanished): both free, the pair waits again.
  const std::vector<FusionCovarianceAnswer> high{answer(1e9)};
  const std::vector<FusionPair> fuse = s.onReply(again->request_id, high, 6.0);
  ASSERT_EQ(fuse.size(), 1u);
  s.onFusionFailed(fuse[0], 7.0);
  EXPECT_EQ(s.stats().fusions_failed, 1u);
  EXPECT_EQ(s.fusionsInProgress(), 0u);
  EXPECT_TRUE(s.graph().contains(1));
  const auto after_failure = s.nextRequest(-1, 7.0);
  ASSERT_TRUE(after_failure.has_value());  // (1, 2), its wait ended at 6.5
  EXPECT_EQ(after_failure->pairs[0].older, 1);
}

// A pair rejected by q again and again waits 5, 10, then the 12 s cap; an error waits the
// base time and does not count; acceptance clears the count.
TEST(FusionSchedulerTest, PairsRejectedByQAgainWaitLongerUpToTheCap) {
  FusionSchedulerConfig config = testConfig();
  config.candidates.min_shared_ratio = 0.5;  // (0, 1) alone: (1, 2) shares 40 %
  config.max_retry_after_s = 12.0;
  FusionScheduler s = threeSubvolumes(config);
  const std::vector<FusionCovarianceAnswer> low{answer(1.0)};
  const auto reject = [&](double now) {
    const auto request = s.nextRequest(-1, now);
    ASSERT_TRUE(request.has_value()) << now;
    ASSERT_EQ(request->pairs.size(), 1u);
    EXPECT_TRUE(s.onReply(request->request_id, low, now).empty());
  };
  reject(0.0);  // 1st: waits 5 s
  EXPECT_FALSE(s.nextRequest(-1, 4.99).has_value());
  reject(5.0);  // 2nd: 10 s
  EXPECT_FALSE(s.nextRequest(-1, 14.99).has_value());
  reject(15.0);  // 3rd: 20 s, capped at 12
  EXPECT_FALSE(s.nextRequest(-1, 26.99).has_value());
  const auto after_cap = s.nextRequest(-1, 27.0);
  ASSERT_TRUE(after_cap.has_value());
  const std::vector<FusionCovarianceAnswer> error{FusionCovarianceAnswer{false, "stale", 0.0}};
  EXPECT_TRUE(s.onReply(after_cap->request_id, error, 27.0).empty());  // waits 5 s
  EXPECT_EQ(s.stats().rejected_by_q, 3u);
  reject(32.0);  // 4th in a row: capped at 12
  EXPECT_FALSE(s.nextRequest(-1, 43.99).has_value());
  const auto accepted = s.nextRequest(-1, 44.0);
  ASSERT_TRUE(accepted.has_value());
  const std::vector<FusionCovarianceAnswer> high{answer(1e9)};
  const std::vector<FusionPair> fuse = s.onReply(accepted->request_id, high, 44.0);
  ASSERT_EQ(fuse.size(), 1u);
  s.onFusionFailed(fuse[0], 45.0);  // not a rejection: the base wait, and the count was reset
  reject(50.0);                     // 1st again: 5 s
  EXPECT_FALSE(s.nextRequest(-1, 54.99).has_value());
  EXPECT_TRUE(s.nextRequest(-1, 55.0).has_value());
}

TEST(FusionSchedulerTest, MalformedRepliesAndVanishedSubvolumesFuseNothing) {
  FusionScheduler s = threeSubvolumes();
  auto request = s.nextRequest(-1, 0.0);
  const std::vector<FusionCovarianceAnswer> two{answer(1e9), answer(1e9)};
  EXPECT_TRUE(s.onReply(request->request_id, two, 0.0).empty());  // 2 answers for 1 pair
  EXPECT_EQ(s.stats().covariance_errors, 1u);
  // A subvolume removed while its pair was asked about: a good answer fuses nothing.
  request = s.nextRequest(-1, 0.0);  // (1, 2): (0, 1) waits
  ASSERT_TRUE(request.has_value());
  s.removeSubvolume(2);
  const std::vector<FusionCovarianceAnswer> one{answer(1e9)};
  EXPECT_TRUE(s.onReply(request->request_id, one, 0.0).empty());
  EXPECT_EQ(s.stats().accepted, 0u);
  EXPECT_EQ(s.fusionsInProgress(), 0u);
}

TEST(FusionSchedulerTest, DisabledProposesNothingButKeepsTheGraph) {
  FusionSchedulerConfig config = testConfig();
  config.enabled = false;
  FusionScheduler s = threeSubvolumes(config);
  EXPECT_EQ(s.graph().weight(0, 1), 60);
  EXPECT_FALSE(s.nextRequest(-1, 0.0).has_value());
  EXPECT_FALSE(s.addKeyframeLandmarks(7, 70, range(0, 3)));  // unknown subvolume
}

TEST(FusionSchedulerTest, InvalidConfigsAreRejected) {
  const auto message = [](FusionSchedulerConfig c) {
    try {
      FusionScheduler s(c);
    } catch (const std::invalid_argument& e) {
      return std::string(e.what());
    }
    return std::string();
  };
  FusionSchedulerConfig c = testConfig();
  c.q_min = 0.0;
  EXPECT_NE(message(c).find("q_min"), std::string::npos);
  c = testConfig();
  c.max_pairs_per_request = 0;
  EXPECT_NE(message(c).find("max_pairs_per_request"), std::string::npos);
  c = testConfig();
  c.reply_timeout_s = 0.0;
  EXPECT_NE(message(c).find("reply_timeout_s"), std::string::npos);
  c = testConfig();
  c.retry_after_s = -1.0;
  EXPECT_NE(message(c).find("retry_after_s"), std::string::npos);
  c = testConfig();
  c.max_retry_after_s = 4.0;  // < retry_after_s
  EXPECT_NE(message(c).find("max_retry_after_s"), std::string::npos);
  c = testConfig();
  c.candidates.min_shared_ratio = 2.0;
  EXPECT_NE(message(c).find("candidates.min_shared_ratio"), std::string::npos);
  EXPECT_EQ(message(testConfig()), "");
}

}  // namespace
}  // namespace cblox
