// TrackerNode with checkpoints: a clean stop writes the map and covers the published ids
// with the lease; a node resumed from that directory restores the map (lost in it, ids
// above the lease, same epoch); a saved map of another camera, or ids published in a newer
// epoch, start a new map in the next epoch instead. loadTrackerResume's cases exactly.

#include <filesystem>
#include <fstream>
#include <mutex>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "daemon/common/lcm_messages.h"
#include "daemon/tracker/tracker_input.h"
#include "daemon/tracker/tracker_node.h"
#include "core/tracking/sparse_map.h"
#include "daemon/tracker/tracker_resume.h"
#include "drivers/open_frame_source.h"

namespace cblox {
namespace {

namespace fs = std::filesystem;

const PinholeIntrinsics kHalfRig{229.0, 229.0, 187.5, 119.5, 376, 240};

struct Log {
  std::mutex mutex;
  std::vector<std::string> lines;
  std::vector<KeyframeInfo> keyframes;
  std::vector<FramePoseReport> poses;
  TrackerNode::Outputs outputs() {
    TrackerNode::Outputs out;
    out.log = [this](const std::string& line) {
      std::lock_guard<std::mutex> lock(mutex);
      lines.push_back(line);
    };
    out.keyframe = [this](const KeyframeInfo& k) {
      std::lock_guard<std::mutex> lock(mutex);
      keyframes.push_back(k);
    };
    out.frame_pose = [this](const FramePoseReport& r) {
      std::lock_guard<std::mutex> lock(mutex);
      poses.push_back(r);
    };
    return out;
  }
  bool said(const std::string& text) {
    std::lock_guard<std::mutex> lock(mutex);
    for (const std::string& line : lines) {
      if (line.find(text) != std::string::npos) return true;
    }
    return false;
  }
};

std::vector<TrackerFrame> roomFrames(size_t n, const PinholeIntrinsics& rig) {
  SourceConfig options;
  options.trajectory = "loop";
  options.max_frames = n;
  options.sim.renderer.rig.stereo = rig;
  std::string error;
  std::unique_ptr<FrameSource> source = openFrameSource("sim:room", options, &error);
  EXPECT_NE(source, nullptr) << error;
  std::vector<TrackerFrame> frames;
  CaptureFrame frame;
  while (source && source->next(&frame, &error) == FrameSource::Status::kFrame) {
    const stereo_pair_t msg = toStereoPairMsg(frame, source->info(), frame.timestamp_ns / 1000);
    TrackerFrame out;
    TrackerProblem problem;
    EXPECT_TRUE(decodeStereoPair(msg, &out, &problem, &error)) << error;
    frames.push_back(std::move(out));
  }
  return frames;
}

void feed(TrackerNode* node, const std::vector<TrackerFrame>& frames, size_t begin, size_t end) {
  for (size_t i = begin; i < end; ++i) {
    ASSERT_TRUE(node->onFrame(frames[i]));
    ASSERT_TRUE(node->waitUntilSettled(std::chrono::seconds(30)));
  }
}

class TrackerResumeTest : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = (fs::path(::testing::TempDir()) /
            ("tracker_resume_" +
             std::string(::testing::UnitTest::GetInstance()->current_test_info()->name())))
               .string();
    fs::remove_all(dir_);
    config_.checkpoint.dir = dir_;
  }
  std::string dir_;
  TrackerNodeConfig config_;
};

TEST_F(TrackerResumeTest, StopCheckpointsAndAResumedNodeContinuesAboveTheLease) {
  const std::vector<TrackerFrame> frames = roomFrames(83, kHalfRig);
  ASSERT_EQ(frames.size(), 83u);
  // Only the checkpoint of each clean stop: under ThreadSanitizer the 80 frames took 52 s,
  // and the default 30 s period added a second checkpoint to the count below.
  config_.checkpoint.period_s = 0.0;
  Log first_log;
  size_t keyframes = 0;
  {
    TrackerNode first(config_, nullptr, first_log.outputs());
    first.start();
    feed(&first, frames, 0, 80);
    first.stop();
    const TrackerStatus s = first.status();
    EXPECT_EQ(s.checkpoints_written, 1u);
    EXPECT_EQ(s.checkpoint_generation, 1u);
    EXPECT_EQ(s.checkpoint_failures, 0u);
    keyframes = s.keyframes;
  }
  ASSERT_GE(keyframes, 2u);
  std::string error;
  const std::optional<IdLease> lease = readIdLease(dir_, &error);
  ASSERT_TRUE(lease.has_value()) << error;
  EXPECT_EQ(lease->map_epoch, 0);
  // Written before keyframe 0 went out (0 + 64), not renewed: no id reached 64.
  EXPECT_EQ(lease->keyframe_floor, 64);
  EXPECT_LT(first_log.keyframes.back().id, 64);

  std::optional<TrackerResume> resume = loadTrackerResume(dir_, &error);
  ASSERT_TRUE(resume.has_value()) << error;
  ASSERT_TRUE(resume->map.has_value());
  EXPECT_EQ(resume->map->map.keyframes.size(), keyframes);
  EXPECT_EQ(resume->map_epoch, 0);
  EXPECT_EQ(resume->keyframe_floor, lease->keyframe_floor);

  // Resumed (no vocabulary: it cannot relocalize, so it stays lost in the restored map).
  Log second_log;
  TrackerNode second(config_, nullptr, second_log.outputs());
  second.resumeFrom(std::move(*resume));
  second.start();
  feed(&second, frames, 80, 83);
  EXPECT_TRUE(second_log.said("resumed map restored: " + std::to_string(keyframes) + " keyframes"));
  TrackerStatus s = second.status();
  EXPECT_EQ(s.resumed_keyframes, keyframes);
  EXPECT_EQ(s.map_epoch, 0);
  EXPECT_EQ(s.frames_lost, 3u);
  EXPECT_EQ(s.frames_not_initialized, 0u);
  second.stop();
  // Its checkpoint lists the restored map again (placeholders up to the floor included).
  const auto again = loadTrackerMap(dir_, &error);
  ASSERT_TRUE(again.has_value()) << error;
  EXPECT_EQ(again->map.keyframes.size(), static_cast<size_t>(lease->keyframe_floor));
  EXPECT_EQ(again->generation, 2u);
}

TEST_F(TrackerResumeTest, ASavedMapOfAnotherCameraStartsANewEpoch) {
  const std::vector<TrackerFrame> frames = roomFrames(12, kHalfRig);
  {
    TrackerNode first(config_, nullptr, {});
    first.start();
    feed(&first, frames, 0, 10);
    first.stop();
  }
  std::string error;
  std::optional<TrackerResume> resume = loadTrackerResume(dir_, &error);
  ASSERT_TRUE(resume && resume->map) << error;
  resume->map->camera.intrinsics.fx *= 2;  // as if saved with another camera
  Log log;
  TrackerNode second(config_, nullptr, log.outputs());
  second.resumeFrom(std::move(*resume));
  second.start();
  feed(&second, frames, 10, 12);
  EXPECT_TRUE(log.said("cannot be continued (its camera"));
  EXPECT_EQ(second.status().map_epoch, 1);
  EXPECT_EQ(second.status().resumed_keyframes, 0u);
  second.stop();
}

TEST_F(TrackerResumeTest, ALeaseFarAboveOrBeyondTheSavedMapStartsANewEpoch) {
  const std::vector<TrackerFrame> frames = roomFrames(10, kHalfRig);
  {
    TrackerNode first(config_, nullptr, {});
    first.start();
    feed(&first, frames, 0, 10);
    first.stop();
  }
  std::string error;
  const auto keyframes =
      static_cast<int64_t>(loadTrackerResume(dir_, &error)->map->map.keyframes.size());
  const struct {
    IdLease lease;
    bool continued;
    int32_t epoch;
  } cases[] = {
      {{0, keyframes + SparseMap::kMaxSkippedKeyframeIds, 100}, true, 0},
      {{0, keyframes + SparseMap::kMaxSkippedKeyframeIds + 1, 100}, false, 1},
      {{0, 64, uint64_t{1} << 40}, false, 1},
      {{3, 64, 100}, false, 4},  // ids of a newer map than the one saved
  };
  for (const auto& c : cases) {
    ASSERT_TRUE(writeIdLease(dir_, c.lease, &error)) << error;
    const std::optional<TrackerResume> resume = loadTrackerResume(dir_, &error);
    ASSERT_TRUE(resume.has_value()) << error;
    EXPECT_EQ(resume->map.has_value(), c.continued) << resume->description;
    EXPECT_EQ(resume->map_epoch, c.epoch) << resume->description;
  }
}

TEST_F(TrackerResumeTest, LoadTrackerResumeCases) {
  std::string error;
  fs::create_directories(dir_);
  // Nothing there: a first start.
  EXPECT_FALSE(loadTrackerResume(dir_, &error).has_value());
  EXPECT_TRUE(error.empty()) << error;
  // Ids published but no map saved: a new map after that epoch.
  ASSERT_TRUE(writeIdLease(dir_, {4, 70, 9000}, &error)) << error;
  std::optional<TrackerResume> resume = loadTrackerResume(dir_, &error);
  ASSERT_TRUE(resume.has_value()) << error;
  EXPECT_FALSE(resume->map.has_value());
  EXPECT_EQ(resume->map_epoch, 5);
  // A damaged lease is an error, not a first start.
  fs::resize_file(fs::path(dir_) / kIdLeaseFileName, 20);
  EXPECT_FALSE(loadTrackerResume(dir_, &error).has_value());
  EXPECT_FALSE(error.empty());
  // So is a damaged map.
  fs::remove(fs::path(dir_) / kIdLeaseFileName);
  std::ofstream(fs::path(dir_) / kTrackerMapFileName) << "not a map";
  EXPECT_FALSE(loadTrackerResume(dir_, &error).has_value());
  EXPECT_NE(error.find(kTrackerMapFileName), std::string::npos) << error;
}

TEST(IdLeaseKeeperTest, RenewsOnlyWhenAnIdReachesTheLeaseOrTheEpochChanges) {
  const fs::path dir = fs::path(::testing::TempDir()) / "id_lease_keeper";
  fs::remove_all(dir);
  IdLeaseKeeper keeper(dir.string(), std::nullopt, 10, 100);
  std::string error;
  ASSERT_TRUE(keeper.cover(0, 0, 5, &error)) << error;
  EXPECT_EQ(keeper.renewals(), 1u);
  EXPECT_EQ(*readIdLease(dir.string(), &error), (IdLease{0, 10, 105}));
  for (int64_t id = 1; id < 10; ++id) ASSERT_TRUE(keeper.cover(0, id, 50, &error));
  EXPECT_EQ(keeper.renewals(), 1u);
  ASSERT_TRUE(keeper.cover(0, 10, 60, &error));  // the keyframe floor reached
  EXPECT_EQ(*readIdLease(dir.string(), &error), (IdLease{0, 20, 160}));
  ASSERT_TRUE(keeper.cover(0, 11, 170, &error));  // the landmark floor passed
  EXPECT_EQ(*readIdLease(dir.string(), &error), (IdLease{0, 21, 270}));
  ASSERT_TRUE(keeper.cover(1, 0, 3, &error));  // a new epoch starts over
  EXPECT_EQ(*readIdLease(dir.string(), &error), (IdLease{1, 10, 103}));
  EXPECT_EQ(keeper.renewals(), 4u);
}

}  // namespace
}  // namespace cblox
