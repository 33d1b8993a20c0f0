// The tracker on simulated stereo: it initialises on the first frame, tracks every frame of a
// known trajectory, and stays close to the exact poses (no local BA here: the tracker alone).

#include "core/tracking/tracker.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <functional>
#include <map>
#include <memory>
#include <optional>
#include <regex>
#include <shared_mutex>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <thread>
#include "core/tracking/frame_builder.h"
#include "core/tracking/local_mapper.h"
#include "drivers/open_frame_source.h"

namespace cblox {
namespace {

struct RunStats {
  int frames = 0, ok = 0, keyframes = 0;
  std::vector<std::pair<int, KeyframeReason>> keyframe_frames;  // frame index, reason
  std::vector<Eigen::Quaterniond> rotations;  // estimated R_C_G of every frame (identity if lost)
  std::vector<int> inliers;                   // TrackingResult::inliers of every frame
  double max_translation_error = 0.0, max_rotation_error_deg = 0.0, path_length = 0.0;
  std::vector<double> track_ms;
  LocalMapperStats mapping;
  /// The last pose local mapping published for each keyframe (its pose batches).
  std::map<KeyframeId, Transformationd> published;
  /// Why each frame that was not tracked failed, by source frame id.
  std::map<int64_t, std::string> lost;
};

/// Called with the map at the end of a run with local mapping, and the run's stats.
using MapCheck = std::function<void(const SparseMap&, const RunStats&)>;

RunStats runTracker(const std::string& spec, const std::string& trajectory, size_t frames,
                    bool local_mapping, const TrackerConfig& config = TrackerConfig{},
                    const LocalMapperConfig& mapping_config = LocalMapperConfig{},
                    const MapCheck& check = nullptr, bool fail_on_lost = true,
                    const std::function<void(SparseMap*)>& prepare = nullptr) {
  SourceConfig options;
  options.trajectory = trajectory;
  options.max_frames = frames;
  std::string error;
  std::unique_ptr<FrameSource> source = openFrameSource(spec, options, &error);
  EXPECT_NE(source, nullptr) << error;
  RunStats stats;
  if (!source) return stats;
  const RectifiedStereoCalibration& calibration = *source->info().stereo;
  const TrackingCamera camera = makeTrackingCamera(calibration.intrinsics, calibration.baseline_m);
  FrameBuilder builder(camera, FrameBuilderConfig{}, nullptr);
  SparseMap map;
  if (prepare) prepare(&map);
  LocalMapper mapper(&map, camera, builder.pyramid(), mapping_config);
  mapper.setPoseCallback([&stats](const KeyframePoseBatch& batch) {
    for (const auto& [id, T_G_C] : batch) stats.published.insert_or_assign(id, T_G_C);
  });
  std::thread mapping_thread;
  if (local_mapping) mapping_thread = std::thread([&] { mapper.run(); });
  Tracker tracker(&map, camera, builder.pyramid(), config, nullptr,
                  local_mapping ? &mapper : nullptr);
  CaptureFrame frame;
  std::optional<Eigen::Vector3d> last_position;
  while (source->next(&frame, &error) == FrameSource::Status::kFrame) {
    const Transformationd T_C_G_true = frame.T_G_C->inverse();
    auto features = builder.fromStereo(frame.left, frame.right);
    const TrackingResult r = tracker.track(static_cast<uint64_t>(frame.frame_id),
                                           frame.timestamp_ns, features, T_C_G_true);
    ++stats.frames;
    stats.track_ms.push_back(r.time_ms);
    stats.rotations.push_back(r.T_C_G ? r.T_C_G->rotation() : Eigen::Quaterniond::Identity());
    stats.inliers.push_back(r.inliers);
    if (r.new_keyframe != nullptr) {
      ++stats.keyframes;
      stats.keyframe_frames.emplace_back(stats.frames - 1, r.keyframe_reason);
    } else {
      EXPECT_EQ(r.keyframe_reason, KeyframeReason::kNone) << "frame " << frame.frame_id;
    }
    if (last_position) stats.path_length += (frame.T_G_C->translation() - *last_position).norm();
    last_position = frame.T_G_C->translation();
    if (r.state != TrackingState::kOk) {
      stats.lost.emplace(frame.frame_id, r.reason);
      if (fail_on_lost) {
        ADD_FAILURE() << "frame " << frame.frame_id << ": " << trackingStateName(r.state) << " "
                      << r.reason;
      }
      continue;
    }
    ++stats.ok;
    const Transformationd T_G_C_est = r.T_C_G->inverse();
    stats.max_translation_error = std::max(
        stats.max_translation_error, (T_G_C_est.translation() - frame.T_G_C->translation()).norm());
    stats.max_rotation_error_deg =
        std::max(stats.max_rotation_error_deg,
                 T_G_C_est.rotation().angularDistance(frame.T_G_C->rotation()) * 180.0 / M_PI);
  }
  if (local_mapping) {
    mapper.waitUntilIdle();
    mapper.stop();
    mapping_thread.join();
    const LocalMapperStats ms = mapper.stats();
    stats.mapping = ms;
    std::printf(
        "local mapping: %lu keyframes, %lu BAs (%lu aborted, last %.1f ms), %lu landmarks "
        "culled, %lu fused\n",
        static_cast<unsigned long>(ms.keyframes_processed),
        static_cast<unsigned long>(ms.bundle_adjustments),
        static_cast<unsigned long>(ms.bundle_adjustments_aborted), ms.last_ba_ms,
        static_cast<unsigned long>(ms.landmarks_culled),
        static_cast<unsigned long>(ms.landmarks_fused));
    if (check) check(map, stats);
  }
  return stats;
}

TEST(TrackerSimTest, TracksTheRoomLoopCloseToTheExactPoses) {
  const RunStats s = runTracker("sim:room", "loop", 120, false);
  ASSERT_EQ(s.frames, 120);
  EXPECT_EQ(s.ok, 120);
  std::sort(const_cast<std::vector<double>&>(s.track_ms).begin(),
            const_cast<std::vector<double>&>(s.track_ms).end());
  std::printf(
      "room: %d frames, %d keyframes, path %.2f m, max error %.4f m %.3f deg, track "
      "median %.2f ms\n",
      s.frames, s.keyframes, s.path_length, s.max_translation_error, s.max_rotation_error_deg,
      s.track_ms[s.track_ms.size() / 2]);
  EXPECT_LT(s.max_translation_error, 0.02 * s.path_length);
  EXPECT_LT(s.max_rotation_error_deg, 1.0);
  EXPECT_GT(s.keyframes, 2);
}

// BoW vectors are lazy: every keyframe has them (computed before other threads see it), a
// frame the motion model tracked without making a keyframe has none; the second frame (no
// velocity yet) is searched against the reference keyframe by BoW, so it has them.
TEST(TrackerSimTest, BowVectorsOnlyWhereTheTrackerNeedsThem) {
  std::string error;
  const auto vocabulary = BinaryVocabulary::load(CBLOX_DEFAULT_VOCABULARY, &error);
  ASSERT_TRUE(vocabulary.has_value()) << error;
  SourceConfig options;
  options.trajectory = "loop";
  options.max_frames = 60;
  std::unique_ptr<FrameSource> source = openFrameSource("sim:room", options, &error);
  ASSERT_NE(source, nullptr) << error;
  const RectifiedStereoCalibration& calibration = *source->info().stereo;
  const TrackingCamera camera = makeTrackingCamera(calibration.intrinsics, calibration.baseline_m);
  FrameBuilder builder(camera, FrameBuilderConfig{}, &*vocabulary);
  SparseMap map;
  KeyframeDatabase database;
  EXPECT_THROW(Tracker(&map, camera, builder.pyramid(), TrackerConfig{}, &database, nullptr),
               std::invalid_argument);  // a database without the vocabulary of its vectors
  TrackerConfig config;
  config.min_frames_between_keyframes = 8;  // keyframes without a local mapper
  config.max_frames_between_keyframes = 8;
  Tracker tracker(&map, camera, builder.pyramid(), config, nullptr, nullptr, &*vocabulary);
  CaptureFrame frame;
  int index = 0, keyframes = 0, without_bow = 0;
  while (source->next(&frame, &error) == FrameSource::Status::kFrame) {
    const std::shared_ptr<FrameFeatures> features = builder.fromStereo(frame.left, frame.right);
    EXPECT_TRUE(features->bow.empty());  // the builder leaves them to the tracker
    const TrackingResult r = tracker.track(static_cast<uint64_t>(frame.frame_id),
                                           frame.timestamp_ns, features, frame.T_G_C->inverse());
    ASSERT_EQ(r.state, TrackingState::kOk) << "frame " << frame.frame_id << ": " << r.reason;
    const bool keyframe = r.new_keyframe != nullptr || r.initialized;
    keyframes += keyframe;
    if (keyframe || index == 1) {
      EXPECT_FALSE(features->bow.empty()) << "frame " << index;
      EXPECT_FALSE(features->feature_vector.empty()) << "frame " << index;
    } else {
      EXPECT_TRUE(features->bow.empty()) << "frame " << index;
      without_bow += features->bow.empty();
    }
    ++index;
  }
  EXPECT_EQ(index, 60);
  EXPECT_GE(keyframes, 3);
  EXPECT_GT(without_bow, 40);
  std::shared_lock<std::shared_mutex> lock(map.mutex());
  for (const Keyframe* k : map.keyframes()) EXPECT_FALSE(k->features().bow.empty());
}

// Each keyframe says which condition made it: with min_frames_between_keyframes and
// max_frames_between_keyframes both 8 ("mapper idle" then never holds before the frame
// count does), the room's keyframes come from the frame count (exactly 8 frames after the
// previous one, or later: c2, fewer inliers than reference_ratio of the reference keyframe's,
// must hold too) or from the tracking itself (sooner).
TEST(TrackerSimTest, KeyframesSayWhichConditionMadeThem) {
  TrackerConfig config;
  config.min_frames_between_keyframes = 8;
  config.max_frames_between_keyframes = 8;
  const RunStats s = runTracker("sim:room", "loop", 80, false, config);
  ASSERT_EQ(s.ok, 80);
  ASSERT_GE(s.keyframe_frames.size(), 2u);
  EXPECT_EQ(s.keyframe_frames.front(), std::make_pair(0, KeyframeReason::kNone));  // the first
  int by_count = 0;
  for (size_t k = 1; k < s.keyframe_frames.size(); ++k) {
    const auto [frame, reason] = s.keyframe_frames[k];
    const int since = frame - s.keyframe_frames[k - 1].first;
    EXPECT_NE(reason, KeyframeReason::kNone) << "frame " << frame;
    EXPECT_NE(reason, KeyframeReason::kMapperIdle) << "frame " << frame;
    if (reason == KeyframeReason::kMaxFrames) {
      EXPECT_GE(since, 8) << "frame " << frame;
      ++by_count;
    } else {
      EXPECT_LT(since, 8) << "frame " << frame << ": " << keyframeReasonName(reason);
    }
  }
  EXPECT_GT(by_count, 0);
  EXPECT_STREQ(keyframeReasonName(KeyframeReason::kClosePoints), "close_points");
}

// The close-point rule made to hold at every frame (tracked_close_min above any count,
// untracked_close_min 0), gated by `gap_frames` alone (no turn, no inlier floor).
TrackerConfig closePointRuleAtEveryFrame(int gap_frames) {
  TrackerConfig config;
  config.tracked_close_min = 1000000;
  config.untracked_close_min = 0;
  config.close_points_min_frames = gap_frames;
  config.close_points_turn_deg = 0.0;
  config.close_points_gap_min_inliers = 0;
  return config;
}

// The close-point keyframes made fewer than `gap_frames` frames after the keyframe before:
// (frame, the keyframe before's frame).
std::vector<std::pair<int, int>> closePointKeyframesInsideGap(const RunStats& s, int gap_frames) {
  std::vector<std::pair<int, int>> inside;
  for (size_t k = 1; k < s.keyframe_frames.size(); ++k) {
    const auto& [frame, reason] = s.keyframe_frames[k];
    const int previous = s.keyframe_frames[k - 1].first;
    if (reason == KeyframeReason::kClosePoints && frame - previous < gap_frames)
      inside.emplace_back(frame, previous);
  }
  return inside;
}

// close_points_min_frames gates the close-point rule by the frames since the last keyframe:
// with the rule made to hold at every frame (tracked_close_min above any count,
// untracked_close_min 0), the room's keyframes come from it, some 1 frame apart; gated at 5
// frames, every close-point keyframe comes at least 5 frames after the one before.
TEST(TrackerSimTest, ClosePointRuleOnlyAfterTheFrameGap) {
  TrackerConfig config = closePointRuleAtEveryFrame(0);  // ORB-SLAM2's rule, no gap
  const auto count = [](const RunStats& s, KeyframeReason reason) {
    return std::count_if(s.keyframe_frames.begin(), s.keyframe_frames.end(),
                         [&](const auto& k) { return k.second == reason; });
  };
  const auto minGap = [](const RunStats& s) {
    int gap = 1000;
    for (size_t k = 1; k < s.keyframe_frames.size(); ++k) {
      if (s.keyframe_frames[k].second != KeyframeReason::kClosePoints) continue;
      gap = std::min(gap, s.keyframe_frames[k].first - s.keyframe_frames[k - 1].first);
    }
    return gap;
  };
  const RunStats always = runTracker("sim:room", "loop", 40, false, config);
  config.close_points_min_frames = 5;
  const RunStats gated = runTracker("sim:room", "loop", 40, false, config);
  ASSERT_EQ(always.ok, 40);
  ASSERT_EQ(gated.ok, 40);
  EXPECT_GT(count(always, KeyframeReason::kClosePoints), 10);
  EXPECT_LT(minGap(always), 5);
  EXPECT_GT(count(gated, KeyframeReason::kClosePoints), 0);
  EXPECT_GE(minGap(gated), 5);
  EXPECT_LT(gated.keyframes, always.keyframes);
  config.close_points_min_frames = -1;
  EXPECT_NE(config.validate().find("close_points_min_frames"), std::string::npos);
}

// close_points_turn_deg waives the gap once the camera has turned that much since the last
// keyframe: with the close-point rule holding at every frame and a gap of 19 frames, the
// room's orbit (turning up to 1 degree a frame) makes close-point keyframes inside the gap,
// each one turned more than 2 degrees from the keyframe before (the rule compares the same
// estimated poses the run returns); without the waiver it makes fewer keyframes.
TEST(TrackerSimTest, ClosePointGapIsWaivedWhileTheCameraTurns) {
  TrackerConfig config = closePointRuleAtEveryFrame(19);
  config.close_points_turn_deg = 2.0;
  const RunStats s = runTracker("sim:room", "orbit", 40, false, config);
  ASSERT_EQ(s.ok, 40);
  const std::vector<std::pair<int, int>> waived = closePointKeyframesInsideGap(s, 19);
  for (const auto& [frame, previous] : waived) {
    const double turned_deg =
        s.rotations[frame].angularDistance(s.rotations[previous]) * 180.0 / M_PI;
    EXPECT_GT(turned_deg, 2.0) << "keyframe at frame " << frame << ", the last at " << previous;
  }
  EXPECT_FALSE(waived.empty());
  config.close_points_turn_deg = 0.0;
  const RunStats gated = runTracker("sim:room", "orbit", 40, false, config);
  EXPECT_LT(gated.keyframes, s.keyframes);
  config.close_points_turn_deg = -1.0;
  EXPECT_NE(config.validate().find("close_points_turn_deg"), std::string::npos);
}

// close_points_gap_min_inliers waives the gap while the frame tracks few inliers: with the
// close-point rule holding at every frame and a gap of 19 frames on the room's straight
// drive, a floor above the frames' inliers brings close-point keyframes inside the gap, each
// at a frame with fewer inliers than the floor; with the floor at 0 none comes inside it.
TEST(TrackerSimTest, ClosePointGapIsWaivedBelowTheInlierFloor) {
  TrackerConfig config = closePointRuleAtEveryFrame(19);
  const RunStats gated = runTracker("sim:room", "loop", 40, false, config);
  ASSERT_EQ(gated.ok, 40);
  EXPECT_TRUE(closePointKeyframesInsideGap(gated, 19).empty());
  // A floor between the frames' smallest and largest inlier counts.
  std::vector<int> sorted(gated.inliers.begin() + 1, gated.inliers.end());
  std::sort(sorted.begin(), sorted.end());
  config.close_points_gap_min_inliers = sorted[sorted.size() / 2];
  const RunStats floored = runTracker("sim:room", "loop", 40, false, config);
  ASSERT_EQ(floored.ok, 40);
  const std::vector<std::pair<int, int>> waived = closePointKeyframesInsideGap(floored, 19);
  EXPECT_FALSE(waived.empty());
  for (const auto& [frame, previous] : waived) {
    EXPECT_LT(floored.inliers[static_cast<size_t>(frame)], config.close_points_gap_min_inliers)
        << "keyframe at frame " << frame << ", the last at " << previous;
  }
  EXPECT_GT(floored.keyframes, gated.keyframes);
  config.close_points_gap_min_inliers = -1;
  EXPECT_NE(config.validate().find("close_points_gap_min_inliers"), std::string::npos);
}

// A turn that starts within one frame: the camera drives along the room at 1 cm a frame, then
// yaws 10 degrees a frame from frame 20 (200 deg/s). At frame 20 the constant-velocity pose
// is off by 10 degrees, about 80 px; the last frame's landmarks and (without a vocabulary)
// the reference keyframe's, searched in ORB-SLAM2's windows, give matches the pose cannot be
// fitted to. The frame is lost, and its reason gives both searches' counts so that a user
// can tell a view without landmarks from a pose the motion model missed. (At 6 degrees a
// frame the same run keeps every frame: the coarse pyramid levels' wider windows carry it.)
TEST(TrackerSimTest, LostFrameReasonGivesTheSearchesCounts) {
  const std::filesystem::path path =
      std::filesystem::path(::testing::TempDir()) / "cblox_turn_onset.tum";
  {
    std::ofstream tum(path);
    Eigen::Matrix3d R0;
    R0.col(0) = Eigen::Vector3d::UnitX();   // camera x: world x
    R0.col(1) = -Eigen::Vector3d::UnitZ();  // camera y: down
    R0.col(2) = Eigen::Vector3d::UnitY();   // camera z: looking along world y
    for (int k = 0; k < 24; ++k) {
      const double yaw = k < 20 ? 0.0 : -10.0 * (k - 19) * M_PI / 180.0;
      const Eigen::Quaterniond q(Eigen::AngleAxisd(yaw, Eigen::Vector3d::UnitZ()) * R0);
      tum << 0.05 * k << " " << 2.0 + 0.01 * k << " 2.0 1.3 " << q.x() << " " << q.y() << " "
          << q.z() << " " << q.w() << "\n";
    }
  }
  const RunStats s = runTracker("sim:room", path.string(), 24, false, TrackerConfig{}, {}, nullptr,
                                /*fail_on_lost=*/false);
  std::filesystem::remove(path);
  ASSERT_EQ(s.frames, 24);
  EXPECT_EQ(s.ok, 20);
  ASSERT_EQ(s.lost.count(20), 1u);
  // "too few matches with the last frame (M matches, I inliers) and the reference keyframe
  // (M matches[, I inliers])": the motion model found its 20 matches, the pose did not fit.
  const std::regex reason(
      "too few matches with the last frame \\(([0-9]+) matches, ([0-9]+) inliers\\) and the "
      "reference keyframe \\(([0-9]+) matches(, [0-9]+ inliers)?\\)");
  std::smatch m;
  ASSERT_TRUE(std::regex_match(s.lost.at(20), m, reason)) << s.lost.at(20);
  EXPECT_GE(std::stoi(m[1]), TrackerConfig{}.min_motion_model_matches);
  EXPECT_LT(std::stoi(m[2]), TrackerConfig{}.min_pose_inliers);
  // Lost since: relocalization has no vocabulary to find keyframes with.
  EXPECT_EQ(s.lost.at(23), "lost: relocalization found no consistent keyframe");
}

// local_ba_max_keyframes bounds the keyframes one local BA optimises: the new keyframe and its
// best covisible ones. On the room every keyframe sees most others, so without the bound the
// window grows past it.
TEST(TrackerSimTest, LocalBundleAdjustmentWindowIsBounded) {
  TrackerConfig tracking;
  tracking.max_frames_between_keyframes = 5;  // keyframes often: a window to bound
  LocalMapperConfig unbounded;
  unbounded.local_ba_max_keyframes = 0;
  LocalMapperConfig bounded;
  bounded.local_ba_max_keyframes = 3;
  const RunStats all = runTracker("sim:room", "loop", 90, true, tracking, unbounded);
  const RunStats few = runTracker("sim:room", "loop", 90, true, tracking, bounded);
  ASSERT_GT(all.mapping.bundle_adjustments, 0u);
  ASSERT_GT(few.mapping.bundle_adjustments, 0u);
  EXPECT_GT(all.mapping.largest_ba_window, 4u);
  EXPECT_EQ(few.mapping.largest_ba_window, 4u);  // the new keyframe and 3 covisible ones
  // The last BA's size: at most the window optimised (fewer when it holds keyframe 0, the
  // gauge), some keyframes fixed around it, and every landmark observed at least once.
  EXPECT_GE(few.mapping.last_ba_free_keyframes, 1u);
  EXPECT_LE(few.mapping.last_ba_free_keyframes, 4u);
  EXPECT_GE(few.mapping.last_ba_fixed_keyframes, 1u);
  EXPECT_GT(few.mapping.last_ba_landmarks, 0u);
  EXPECT_GE(few.mapping.last_ba_observations, few.mapping.last_ba_landmarks);
  LocalMapperConfig negative;
  negative.local_ba_max_keyframes = -1;
  EXPECT_NE(negative.validate().find("local_ba_max_keyframes"), std::string::npos);
}

// While a loop correction is half done (its essential graph solved without the map's lock,
// part of the map corrected and part not), local mapping starts no local BA: the keyframes
// it would hold fixed may be uncorrected. The same run without it runs local BAs.
TEST(TrackerSimTest, NoLocalBundleAdjustmentStartsWhileACorrectionIsHalfDone) {
  TrackerConfig tracking;
  tracking.max_frames_between_keyframes = 5;
  const RunStats normal = runTracker("sim:room", "loop", 90, true, tracking);
  const RunStats pending =
      runTracker("sim:room", "loop", 90, true, tracking, {}, nullptr, true, [](SparseMap* map) {
        std::unique_lock<std::shared_mutex> lock(map->mutex());
        map->setCorrectionPending(true);
      });
  EXPECT_GT(normal.mapping.bundle_adjustments, 0u);
  EXPECT_EQ(pending.ok, 90);
  EXPECT_GT(pending.mapping.keyframes_processed, 3u);
  EXPECT_EQ(pending.mapping.bundle_adjustments, 0u);
  EXPECT_GT(pending.mapping.bundle_adjustments_discarded, 0u);
}

// Keyframe culling with the dense mapper's anchors: a culled keyframe stays tied to its first
// good ancestor, and every pose batch that moves the ancestor carries the culled keyframe's
// pose too (SparseMap::moveCulledKeyframes), so a subvolume anchored on it goes on moving with
// the map. With a keyframe about every 2 frames many are redundant and culled; at the end, the last
// published pose of every culled keyframe is its ancestor's current pose times T_A_K.
TEST(TrackerSimTest, CulledKeyframesFollowTheirAncestorInThePublishedPoses) {
  TrackerConfig tracking;
  tracking.max_frames_between_keyframes = 2;
  tracking.reference_ratio = 0.99;  // c2 holds at almost every frame: keyframes every 2 frames
  LocalMapperConfig culling;
  culling.cull_keyframes = true;
  size_t culled_checked = 0;
  const RunStats s = runTracker(
      "sim:room", "loop", 120, true, tracking, culling,
      [&](const SparseMap& map, const RunStats& run) {
        std::shared_lock<std::shared_mutex> lock(map.mutex());
        for (const std::unique_ptr<Keyframe>& k : map.allKeyframes()) {
          if (!k->bad()) continue;
          const std::optional<KeyframeAncestor> a = SparseMap::goodAncestor(k.get());
          ASSERT_TRUE(a.has_value()) << "keyframe " << k->id;
          const auto published = run.published.find(k->id);
          const auto ancestor = run.published.find(a->ancestor->id);
          // Never moved since the cull (its ancestor neither): nothing to follow.
          if (ancestor == run.published.end()) continue;
          if (published == run.published.end()) continue;  // never published
          const Transformationd expected = a->ancestor->T_G_C() * a->T_A_K;
          EXPECT_TRUE(published->second.isApprox(expected, 1e-9)) << "keyframe " << k->id;
          EXPECT_TRUE(k->T_G_C().isApprox(expected, 1e-9)) << "keyframe " << k->id;
          ++culled_checked;
        }
      });
  EXPECT_EQ(s.ok, 120);
  EXPECT_GT(s.mapping.keyframes_culled, 0u);
  EXPECT_GT(culled_checked, 0u);
  std::printf("[ measured ] %d keyframes made, %lu culled, %zu followed their ancestor\n",
              s.keyframes, static_cast<unsigned long>(s.mapping.keyframes_culled), culled_checked);
}

// A loop correction (or a global BA) that moves the map between the moment a frame is tracked
// and the moment its keyframe is inserted: the frame follows its reference keyframe, so the
// keyframe is made at the corrected pose and its new landmarks with it. Without this the
// keyframe kept the uncorrected pose (1.5 m and 8 degrees off here); in the running process
// that put the map's newest keyframes beside the corrected ones, and the next loops found them
// metres apart. The map is moved rigidly (G' = S G) once at a frame that makes a keyframe and
// once at one that does not; every later frame must be at S times its true pose.
TEST(TrackerSimTest, AFrameFollowsAMapCorrectedWhileItWasBeingTracked) {
  std::string error;
  SourceConfig options;
  options.trajectory = "loop";
  options.max_frames = 70;
  std::unique_ptr<FrameSource> source = openFrameSource("sim:room", options, &error);
  ASSERT_NE(source, nullptr) << error;
  const RectifiedStereoCalibration& calibration = *source->info().stereo;
  const TrackingCamera camera = makeTrackingCamera(calibration.intrinsics, calibration.baseline_m);
  FrameBuilder builder(camera, FrameBuilderConfig{}, nullptr);
  SparseMap map;
  TrackerConfig config;
  config.min_frames_between_keyframes = 8;  // keyframes without a local mapper
  config.max_frames_between_keyframes = 8;
  Tracker tracker(&map, camera, builder.pyramid(), config, nullptr, nullptr);
  // Each move: 8 degrees about the vertical and 1.5 m sideways.
  const Transformationd S(
      Eigen::Quaterniond(Eigen::AngleAxisd(8.0 * M_PI / 180.0, Eigen::Vector3d::UnitY())),
      Eigen::Vector3d(1.5, 0.0, 0.4));
  Transformationd T_Gnow_G;  // every move so far
  int index = 0, moved_at_keyframe = -1, moved_at_frame = -1;
  tracker.setAfterTrackingHook([&](bool makes_keyframe) {
    const bool move = (makes_keyframe && moved_at_keyframe < 0 && index >= 20) ||
                      (!makes_keyframe && moved_at_keyframe >= 0 && moved_at_frame < 0 &&
                       index >= moved_at_keyframe + 10);
    if (!move) return;
    (makes_keyframe ? moved_at_keyframe : moved_at_frame) = index;
    std::unique_lock<std::shared_mutex> lock(map.mutex());
    map.bumpChangeIndex();
    for (Keyframe* k : map.keyframes()) k->setPose(k->T_C_G() * S.inverse());
    for (Landmark* l : map.landmarks()) {
      l->setPosition(S * l->position());
      l->updateNormalAndDepth(builder.pyramid());
    }
    T_Gnow_G = S * T_Gnow_G;
  });
  CaptureFrame frame;
  double max_error_after = 0.0;
  int checked = 0;
  while (source->next(&frame, &error) == FrameSource::Status::kFrame) {
    const std::shared_ptr<FrameFeatures> features = builder.fromStereo(frame.left, frame.right);
    const TrackingResult r = tracker.track(static_cast<uint64_t>(frame.frame_id),
                                           frame.timestamp_ns, features, frame.T_G_C->inverse());
    ASSERT_EQ(r.state, TrackingState::kOk) << "frame " << index << ": " << r.reason;
    if (index == moved_at_keyframe) {
      ASSERT_NE(r.new_keyframe, nullptr);
      std::shared_lock<std::shared_mutex> lock(map.mutex());
      const Transformationd expected = T_Gnow_G * *frame.T_G_C;
      EXPECT_LT((r.new_keyframe->T_G_C().translation() - expected.translation()).norm(), 0.05)
          << "the keyframe made across the correction";
      EXPECT_LT(
          r.new_keyframe->T_G_C().rotation().angularDistance(expected.rotation()) * 180.0 / M_PI,
          0.5);
    }
    if (moved_at_keyframe >= 0 && index > moved_at_keyframe) {
      // The frame the map moved under (not a keyframe) was published at its tracked pose;
      // every frame after it is in the moved map.
      const bool published_before_move = index == moved_at_frame;
      const Transformationd expected =
          (published_before_move ? S.inverse() * T_Gnow_G : T_Gnow_G) * *frame.T_G_C;
      const double e = (r.T_C_G->inverse().translation() - expected.translation()).norm();
      max_error_after = std::max(max_error_after, e);
      EXPECT_LT(e, 0.05) << "frame " << index;
      ++checked;
    }
    ++index;
  }
  EXPECT_EQ(index, 70);
  EXPECT_GE(moved_at_keyframe, 20);
  EXPECT_GT(moved_at_frame, moved_at_keyframe);
  EXPECT_GT(checked, 30);
  std::printf(
      "[ measured ] map moved at frames %d (keyframe) and %d; %d frames after, max error "
      "%.4f m\n",
      moved_at_keyframe, moved_at_frame, checked, max_error_after);
}

}  // namespace
}  // namespace cblox
