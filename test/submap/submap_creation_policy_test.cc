#include "core/submap/submap_creation_policy.h"

#include <limits>
#include <stdexcept>

#include <gtest/gtest.h>

#include "core/submap/submap_collection.h"

namespace cblox {
namespace {

using Action = SubmapCreationPolicy::FrameAction;
using Pending = SubmapCreationPolicy::Pending;

TEST(SubmapCreationPolicyConfig, ValidateNamesTheField) {
  SubmapCreationPolicyConfig config;
  EXPECT_EQ(config.validate(), "");
  config.max_keyframes_per_subvolume = 0;
  EXPECT_NE(config.validate().find("max_keyframes_per_subvolume"), std::string::npos);
  EXPECT_THROW(SubmapCreationPolicy{config}, std::invalid_argument);
  config = SubmapCreationPolicyConfig{};
  config.max_anchor_distance_m = -1.0;
  EXPECT_NE(config.validate().find("max_anchor_distance_m"), std::string::npos);
  config.max_anchor_distance_m = std::numeric_limits<double>::infinity();
  EXPECT_NE(config.validate().find("max_anchor_distance_m"), std::string::npos);
  config = SubmapCreationPolicyConfig{};
  config.revisit_anchor_distance_m = -0.5;
  EXPECT_NE(config.validate().find("revisit_anchor_distance_m"), std::string::npos);
  config.revisit_anchor_distance_m = std::numeric_limits<double>::quiet_NaN();
  EXPECT_NE(config.validate().find("revisit_anchor_distance_m"), std::string::npos);
}

// With revisit_anchor_distance_m, a keyframe closer than that to an older subvolume's
// anchor starts a new submap (tracking returned to a mapped place), unless the active
// submap's anchor is itself within that distance of the older anchor (it already started
// there); the reason is reported.
TEST(SubmapCreationPolicy, AKeyframeNearAnOlderAnchorStartsARevisitSubmap) {
  using Reason = SubmapCreationPolicy::Reason;
  SubmapCreationPolicyConfig config;
  config.max_keyframes_per_subvolume = 100;
  config.revisit_anchor_distance_m = 1.0;
  SubmapCreationPolicy policy(config);
  EXPECT_EQ(policy.lastReason(), Reason::kNone);
  // The active submap is anchored at x = 10; older anchors at x = 0 and x = 5.
  Submap active(2, LayerConfig{},
                Transformationd(Eigen::Quaterniond::Identity(), Eigen::Vector3d(10.0, 0.0, 0.0)),
                100, 0);
  const std::vector<Eigen::Vector3d> older = {Eigen::Vector3d(0.0, 0.0, 0.0),
                                              Eigen::Vector3d(5.0, 0.0, 0.0)};
  EXPECT_FALSE(policy.onKeyframe(&active, false, Eigen::Vector3d(3.0, 0.0, 0.0), older));
  EXPECT_FALSE(policy.onKeyframe(&active, false, Eigen::Vector3d(5.0, 1.0, 0.0), older));  // 1 m
  EXPECT_TRUE(policy.onKeyframe(&active, false, Eigen::Vector3d(5.0, 0.0, 0.99), older));
  EXPECT_EQ(policy.lastReason(), Reason::kRevisit);
  EXPECT_STREQ(SubmapCreationPolicy::reasonName(policy.lastReason()), "revisit");
  // The revisit submap anchored 0.6 m before the old anchor: the next keyframes near that
  // anchor join it, the next old anchor starts another one.
  Submap revisit(3, LayerConfig{},
                 Transformationd(Eigen::Quaterniond::Identity(), Eigen::Vector3d(4.4, 0.0, 0.0)),
                 101, 0);
  EXPECT_FALSE(policy.onKeyframe(&revisit, false, Eigen::Vector3d(5.3, 0.0, 0.0), older));
  EXPECT_FALSE(policy.onKeyframe(&revisit, false, Eigen::Vector3d(0.5, 0.0, 0.0)));  // no anchors
  EXPECT_TRUE(policy.onKeyframe(&revisit, false, Eigen::Vector3d(0.5, 0.0, 0.0), older));
  // Without a position the rule cannot apply; the keyframe limit still does, and says so.
  EXPECT_FALSE(policy.onKeyframe(&active, false, std::nullopt, older));
  SubmapCreationPolicy small(SubmapCreationPolicyConfig{1, 0.0, 1.0});
  EXPECT_TRUE(small.onKeyframe(&active, false, Eigen::Vector3d(5.0, 0.0, 0.0), older));
  EXPECT_EQ(small.lastReason(), Reason::kKeyframeLimit);
  EXPECT_TRUE(small.onKeyframe(nullptr, false, Eigen::Vector3d(5.0, 0.0, 0.0), older));
  EXPECT_EQ(small.lastReason(), Reason::kNoActiveSubmap);
  EXPECT_TRUE(small.onKeyframe(&active, true));
  EXPECT_EQ(small.lastReason(), Reason::kNewMap);
  // Off (0): never.
  SubmapCreationPolicy off(SubmapCreationPolicyConfig{100});
  EXPECT_FALSE(off.onKeyframe(&active, false, Eigen::Vector3d(0.0, 0.0, 0.0), older));
}

// With revisit_after_frames = 3, three frames in a row tracked against a keyframe whose home
// is the same older submap (another anchor than the active one's) start a revisit submap; a
// frame at home (the active submap, or one sharing its anchor), without a home, or voting for
// another home starts the count again. A pending keyframe-limit decision is cleared (the new
// submap has one keyframe). Off (0): never.
TEST(SubmapCreationPolicy, FramesTrackedInAnOlderSubmapStartARevisitSubmap) {
  using Home = SubmapCreationPolicy::ReferenceHome;
  using Reason = SubmapCreationPolicy::Reason;
  SubmapCreationPolicyConfig config;
  config.max_keyframes_per_subvolume = 1;
  config.revisit_after_frames = 3;
  EXPECT_EQ(config.validate(), "");
  SubmapCreationPolicy policy(config);
  Submap active(5, LayerConfig{}, Transformationd(), 50, 0);  // full: 1 keyframe
  ASSERT_EQ(policy.onFramePose(&active, false), Action::kIntegrate);
  ASSERT_EQ(policy.pending(), Pending::kKeyframeLimit);
  const Home old_home{2, 20}, other_home{3, 30};
  EXPECT_FALSE(policy.onFrameReference(active, old_home));
  EXPECT_FALSE(policy.onFrameReference(active, old_home));
  EXPECT_FALSE(policy.onFrameReference(active, Home{5, 50}));  // at home: votes cleared
  EXPECT_FALSE(policy.onFrameReference(active, old_home));
  EXPECT_FALSE(policy.onFrameReference(active, old_home));
  EXPECT_FALSE(policy.onFrameReference(active, std::nullopt));  // no home: cleared
  EXPECT_FALSE(policy.onFrameReference(active, old_home));
  EXPECT_FALSE(policy.onFrameReference(active, old_home));
  EXPECT_FALSE(policy.onFrameReference(active, Home{1, 50}));  // shares the anchor: cleared
  EXPECT_FALSE(policy.onFrameReference(active, old_home));
  EXPECT_FALSE(policy.onFrameReference(active, other_home));  // another home: counts anew
  EXPECT_FALSE(policy.onFrameReference(active, other_home));
  EXPECT_EQ(policy.lastReason(), Reason::kNone);
  EXPECT_TRUE(policy.onFrameReference(active, other_home));
  EXPECT_EQ(policy.lastReason(), Reason::kRevisitFrames);
  EXPECT_STREQ(SubmapCreationPolicy::reasonName(policy.lastReason()),
               "tracked in an older subvolume");
  EXPECT_EQ(policy.pending(), Pending::kNone);
  // The votes start from zero after a revisit submap.
  EXPECT_FALSE(policy.onFrameReference(active, other_home));

  // revisit_max_frames: the revisit submap (anchored at 30) takes that many frames at home,
  // then a fresh one starts; frames elsewhere do not count. Not for other submaps.
  config.revisit_max_frames = 4;
  SubmapCreationPolicy renewing(config);
  ASSERT_FALSE(renewing.onFrameReference(active, other_home));
  ASSERT_FALSE(renewing.onFrameReference(active, other_home));
  ASSERT_TRUE(renewing.onFrameReference(active, other_home));  // revisit submap at 30
  Submap revisit(6, LayerConfig{}, Transformationd(), 30, 0);
  EXPECT_FALSE(renewing.onFrameReference(revisit, other_home));
  EXPECT_FALSE(renewing.onFrameReference(revisit, Home{6, 30}));
  EXPECT_FALSE(renewing.onFrameReference(revisit, old_home));  // a vote, not a frame at home
  EXPECT_FALSE(renewing.onFrameReference(revisit, other_home));
  EXPECT_TRUE(renewing.onFrameReference(revisit, other_home));  // the 4th at home
  EXPECT_EQ(renewing.lastReason(), Reason::kRevisitFrames);
  for (int i = 0; i < 3; ++i) EXPECT_FALSE(renewing.onFrameReference(revisit, other_home));
  EXPECT_TRUE(renewing.onFrameReference(revisit, other_home));
  // A keyframe while the revisit submap is active starts a new submap: the revisit ends, and
  // frames at home in it are no longer counted.
  EXPECT_TRUE(renewing.onKeyframe(&revisit));
  EXPECT_EQ(renewing.lastReason(), Reason::kRevisitEnded);
  EXPECT_STREQ(SubmapCreationPolicy::reasonName(renewing.lastReason()),
               "new keyframe after a revisit");
  for (int i = 0; i < 8; ++i) EXPECT_FALSE(renewing.onFrameReference(revisit, other_home));

  SubmapCreationPolicyConfig off_config;
  EXPECT_EQ(off_config.revisit_after_frames, 10);  // the default
  off_config.revisit_after_frames = 0;
  SubmapCreationPolicy off(off_config);
  for (int i = 0; i < 20; ++i) EXPECT_FALSE(off.onFrameReference(active, old_home));
  config.revisit_after_frames = -1;
  EXPECT_NE(config.validate().find("revisit_after_frames"), std::string::npos);
  config.revisit_after_frames = 1;
  config.revisit_max_frames = -1;
  EXPECT_NE(config.validate().find("revisit_max_frames"), std::string::npos);
}

// After a tracking jump, a frame whose reference keyframe lies in an older submap starts a
// revisit submap there at once (onJumpReference) instead of waiting for the next keyframe;
// its home must be another submap than the active one, a jump must be pending, and the
// frames rule must be on.
TEST(SubmapCreationPolicy, AJumpIntoAnOlderSubmapStartsARevisitSubmapAtOnce) {
  using Home = SubmapCreationPolicy::ReferenceHome;
  using Reason = SubmapCreationPolicy::Reason;
  SubmapCreationPolicyConfig config;
  config.revisit_max_frames = 3;
  SubmapCreationPolicy policy(config);
  Submap active(5, LayerConfig{}, Transformationd(), 50, 0);
  const Home old_home{2, 20};
  // No jump pending: nothing to do.
  ASSERT_EQ(policy.onFramePose(&active, false), Action::kIntegrate);
  EXPECT_FALSE(policy.onJumpReference(&active, old_home));
  // A jump: frames wait, unless their reference keyframe has an older home.
  ASSERT_EQ(policy.onFramePose(&active, true), Action::kWaitForAnchor);
  EXPECT_FALSE(policy.onJumpReference(&active, std::nullopt));
  EXPECT_FALSE(policy.onJumpReference(&active, Home{5, 50}));  // the active submap itself
  EXPECT_FALSE(policy.onJumpReference(&active, Home{1, 50}));  // shares its anchor
  EXPECT_EQ(policy.pending(), Pending::kTrackingJump);
  EXPECT_TRUE(policy.onJumpReference(&active, old_home));
  EXPECT_EQ(policy.lastReason(), Reason::kRevisitAfterJump);
  EXPECT_STREQ(SubmapCreationPolicy::reasonName(policy.lastReason()),
               "tracked in an older subvolume after a jump");
  EXPECT_EQ(policy.pending(), Pending::kNone);
  // The new submap is a revisit submap: frames at home renew it after revisit_max_frames, and
  // a keyframe ends it.
  Submap revisit(6, LayerConfig{}, Transformationd(), 20, 0);
  EXPECT_EQ(policy.onFramePose(&revisit, false), Action::kIntegrate);
  EXPECT_FALSE(policy.onFrameReference(revisit, old_home));
  EXPECT_FALSE(policy.onFrameReference(revisit, old_home));
  EXPECT_TRUE(policy.onFrameReference(revisit, old_home));
  EXPECT_EQ(policy.lastReason(), Reason::kRevisitFrames);
  EXPECT_TRUE(policy.onKeyframe(&revisit));
  EXPECT_EQ(policy.lastReason(), Reason::kRevisitEnded);
  // With the frames rule off, a jump always waits for its keyframe.
  config.revisit_after_frames = 0;
  SubmapCreationPolicy off(config);
  ASSERT_EQ(off.onFramePose(&active, true), Action::kWaitForAnchor);
  EXPECT_FALSE(off.onJumpReference(&active, old_home));
  EXPECT_EQ(off.pending(), Pending::kTrackingJump);
}

// The policy says why it asked for each new submap (the mapper logs it).
TEST(SubmapCreationPolicy, ReportsWhyASubmapWasCreated) {
  using Reason = SubmapCreationPolicy::Reason;
  SubmapCreationPolicy policy(SubmapCreationPolicyConfig{2});
  EXPECT_EQ(policy.lastReason(), Reason::kNone);
  EXPECT_STREQ(SubmapCreationPolicy::reasonName(Reason::kNone), "none");
  Submap active(0, LayerConfig{}, Transformationd(), 100, 0);
  EXPECT_TRUE(policy.onKeyframe(nullptr));
  EXPECT_EQ(policy.lastReason(), Reason::kNoActiveSubmap);
  EXPECT_FALSE(policy.onKeyframe(&active));  // 1 of 2 keyframes: joins, the reason stays
  EXPECT_EQ(policy.lastReason(), Reason::kNoActiveSubmap);
  EXPECT_TRUE(policy.onKeyframe(&active, /*starts_new_map=*/true));
  EXPECT_EQ(policy.lastReason(), Reason::kNewMap);
  EXPECT_STREQ(SubmapCreationPolicy::reasonName(policy.lastReason()), "new map");
  EXPECT_EQ(policy.onFramePose(&active, /*tracking_jump=*/true),
            SubmapCreationPolicy::FrameAction::kWaitForAnchor);
  EXPECT_TRUE(policy.onKeyframe(&active));
  EXPECT_EQ(policy.lastReason(), Reason::kTrackingJump);
  active.addKeyframe(101);
  EXPECT_TRUE(policy.onKeyframe(&active));
  EXPECT_EQ(policy.lastReason(), Reason::kKeyframeLimit);
  EXPECT_STREQ(SubmapCreationPolicy::reasonName(policy.lastReason()), "keyframe limit");
  active.finish();
  EXPECT_TRUE(policy.onKeyframe(&active));
  EXPECT_EQ(policy.lastReason(), Reason::kNoActiveSubmap);
}

// With max_anchor_distance_m, a keyframe farther than that from the active submap's anchor
// (its current T_G_M) anchors a new submap, whatever the keyframe count; at exactly the
// distance, or without a position, it joins.
TEST(SubmapCreationPolicy, AKeyframeTooFarFromTheAnchorAnchorsANewSubmap) {
  SubmapCreationPolicyConfig config;
  config.max_keyframes_per_subvolume = 100;
  config.max_anchor_distance_m = 3.0;
  SubmapCreationPolicy policy(config);
  const Transformationd T_G_M(Eigen::Quaterniond::Identity(), Eigen::Vector3d(1.0, 2.0, 0.0));
  Submap active(0, LayerConfig{}, T_G_M, 100, 0);
  EXPECT_FALSE(policy.onKeyframe(&active, false, Eigen::Vector3d(4.0, 2.0, 0.0)));  // 3 m
  EXPECT_TRUE(policy.onKeyframe(&active, false, Eigen::Vector3d(1.0, 2.0, 3.01)));
  EXPECT_EQ(policy.lastReason(), SubmapCreationPolicy::Reason::kAnchorDistance);
  EXPECT_STREQ(SubmapCreationPolicy::reasonName(policy.lastReason()), "anchor distance");
  EXPECT_FALSE(policy.onKeyframe(&active, false));  // no position: the count rule only
  // The anchor moved by a correction: the distance is to where it is now.
  active.setT_G_M(Transformationd(Eigen::Quaterniond::Identity(), Eigen::Vector3d(1.0, 2.0, 2.0)));
  EXPECT_FALSE(policy.onKeyframe(&active, false, Eigen::Vector3d(1.0, 2.0, 3.01)));
  // Off (0): never.
  SubmapCreationPolicy off(SubmapCreationPolicyConfig{100});
  EXPECT_FALSE(off.onKeyframe(&active, false, Eigen::Vector3d(1e6, 0.0, 0.0)));
}

TEST(SubmapCreationPolicy, RuleNewSubmapAfterNKeyframesOrOnATrackingJump) {
  const SubmapCreationPolicy policy(SubmapCreationPolicyConfig{3});
  Submap submap(0, LayerConfig{}, Transformationd(), 100, 0);  // anchor = keyframe 1 of 3
  EXPECT_FALSE(policy.needsNewSubmap(submap, false));
  EXPECT_TRUE(policy.needsNewSubmap(submap, true));
  submap.addKeyframe(101);
  EXPECT_FALSE(policy.needsNewSubmap(submap, false));
  submap.addKeyframe(101);  // a repeated keyframe does not count twice
  EXPECT_FALSE(policy.needsNewSubmap(submap, false));
  submap.addKeyframe(102);
  EXPECT_TRUE(policy.needsNewSubmap(submap, false));
  Submap other(1, LayerConfig{}, Transformationd(), 200, 0);
  other.finish();
  EXPECT_TRUE(policy.needsNewSubmap(other, false));
}

// The mapper's loop: frames before the first keyframe wait; each submap takes N keyframes;
// frames keep being integrated after the limit until the next keyframe anchors a new
// submap; a tracking jump makes frames wait and the next keyframe anchor a new submap.
TEST(SubmapCreationPolicy, DrivesTheMapperLoop) {
  SubmapCollection collection(SubmapCollectionConfig{});
  SubmapCreationPolicy policy(SubmapCreationPolicyConfig{2});
  KeyframeId next_keyframe = 0;
  const auto keyframe = [&] {
    const KeyframeId id = next_keyframe++;
    const Transformationd T_G_K(Eigen::Quaterniond::Identity(),
                                Eigen::Vector3d(static_cast<double>(id), 0, 0));
    if (policy.onKeyframe(collection.activeSubmap().get())) {
      collection.createSubmap(T_G_K, id, id * 1000);
      return true;
    }
    collection.activeSubmap()->addKeyframe(id);
    return false;
  };
  const auto frame = [&](bool jump) {
    return policy.onFramePose(collection.activeSubmap().get(), jump);
  };

  EXPECT_EQ(frame(false), Action::kWaitForAnchor);  // no submap yet
  EXPECT_EQ(policy.pending(), Pending::kNoActiveSubmap);
  EXPECT_TRUE(keyframe());  // keyframe 0 anchors submap 0
  EXPECT_EQ(policy.pending(), Pending::kNone);
  EXPECT_EQ(frame(false), Action::kIntegrate);
  EXPECT_FALSE(keyframe());                     // keyframe 1: submap 0 has 2 keyframes now
  EXPECT_EQ(frame(false), Action::kIntegrate);  // still integrated...
  EXPECT_EQ(policy.pending(), Pending::kKeyframeLimit);
  EXPECT_TRUE(keyframe());  // ...until keyframe 2 anchors submap 1
  EXPECT_EQ(collection.size(), 2u);
  EXPECT_EQ(collection.activeSubmap()->anchorKeyframe(), 2);
  EXPECT_TRUE(collection.activeSubmap()->T_G_M().translation().isApprox(Eigen::Vector3d(2, 0, 0)));
  EXPECT_EQ(collection.getSubmap(0)->keyframeIds(), (std::vector<KeyframeId>{0, 1}));

  // A keyframe limit reached without frames in between is still applied.
  EXPECT_FALSE(keyframe());  // keyframe 3 into submap 1
  EXPECT_TRUE(keyframe());   // keyframe 4 anchors submap 2
  EXPECT_EQ(collection.size(), 3u);

  // Tracking jump: frames wait until the next keyframe anchors a new submap.
  EXPECT_EQ(frame(false), Action::kIntegrate);
  EXPECT_EQ(frame(true), Action::kWaitForAnchor);
  EXPECT_EQ(policy.pending(), Pending::kTrackingJump);
  EXPECT_EQ(frame(false), Action::kWaitForAnchor);
  EXPECT_TRUE(keyframe());  // keyframe 5 anchors submap 3 though submap 2 had room
  EXPECT_EQ(collection.activeSubmap()->anchorKeyframe(), 5);
  EXPECT_EQ(frame(false), Action::kIntegrate);
  EXPECT_EQ(collection.size(), 4u);

  // No new submap otherwise.
  EXPECT_EQ(frame(false), Action::kIntegrate);
  EXPECT_EQ(policy.pending(), Pending::kNone);

  // A jump overrides a pending keyframe limit; reset() forgets the pending decision.
  EXPECT_FALSE(keyframe());  // keyframe 6: submap 3 full
  EXPECT_EQ(frame(false), Action::kIntegrate);
  EXPECT_EQ(frame(true), Action::kWaitForAnchor);
  EXPECT_EQ(policy.pending(), Pending::kTrackingJump);
  policy.reset();
  EXPECT_EQ(policy.pending(), Pending::kNone);
}

// A jump whose keyframe was applied before its frame: the submap that keyframe anchored is no
// older than the frame, so the jump is answered and the frame integrated; a keyframe of a new
// map (the tracker reset) anchors a submap of its own even when the active one has room.
TEST(SubmapCreationPolicy, AJumpAnsweredByANewerSubmapAndANewMapsKeyframe) {
  SubmapCreationPolicy policy(SubmapCreationPolicyConfig{10});
  Submap anchored(0, LayerConfig{}, Transformationd(), 100, /*creation_time_ns=*/5'000);
  EXPECT_EQ(policy.onFramePose(&anchored, true, 5'000), Action::kIntegrate);  // same time
  EXPECT_EQ(policy.pending(), Pending::kNone);
  EXPECT_EQ(policy.onFramePose(&anchored, true, 4'000), Action::kIntegrate);      // older frame
  EXPECT_EQ(policy.onFramePose(&anchored, true, 5'001), Action::kWaitForAnchor);  // newer
  EXPECT_EQ(policy.pending(), Pending::kTrackingJump);
  policy.reset();
  EXPECT_EQ(policy.onFramePose(&anchored, true), Action::kWaitForAnchor);  // time unknown
  policy.reset();
  EXPECT_FALSE(policy.onKeyframe(&anchored));  // room for 9 more keyframes
  EXPECT_TRUE(policy.onKeyframe(&anchored, /*starts_new_map=*/true));
  EXPECT_EQ(policy.pending(), Pending::kNone);
}

}  // namespace
}  // namespace cblox
