#include <unistd.h>

#include <cmath>
#include <filesystem>
#include <limits>
#include <string>
#include <thread>
#include <vector>

#include <gtest/gtest.h>

#include "core/common/in_tray.h"
#include "core/mapping/map_epoch_key.h"
#include "core/mapping/output_path.h"
#include "core/mapping/pose_buffer.h"

namespace cblox {
namespace {

TimedPose poseAt(int64_t utime, double x, bool ok = true, bool jump = false, int32_t epoch = 0) {
  TimedPose pose;
  pose.utime = utime;
  pose.T_G_C = Transformationd(Eigen::Quaterniond(Eigen::AngleAxisd(x, Eigen::Vector3d::UnitZ())),
                               Eigen::Vector3d(x, 0.0, 0.0));
  pose.tracking_ok = ok;
  pose.jump = jump;
  pose.epoch = epoch;
  return pose;
}

TEST(PoseBufferTest, InterpolatesBetweenNeighboursAndReturnsExactMatches) {
  PoseBuffer buffer(PoseBuffer::Config{});
  ASSERT_EQ(buffer.add(poseAt(1'000'000, 0.0)), PoseBuffer::AddResult::kAdded);
  ASSERT_EQ(buffer.add(poseAt(1'100'000, 1.0)), PoseBuffer::AddResult::kAdded);
  Transformationd T;
  bool jump = true;
  ASSERT_EQ(buffer.lookup(1'025'000, &T, &jump), PoseBuffer::Lookup::kFound);
  // A quarter of the way along the geodesic (screw motion) between the two poses.
  EXPECT_TRUE(T.isApprox(
      Transformationd::interpolate(poseAt(0, 0.0).T_G_C, poseAt(0, 1.0).T_G_C, 0.25), 1e-12));
  EXPECT_NEAR(Eigen::AngleAxisd(T.rotation()).angle(), 0.25, 1e-12);
  EXPECT_FALSE(jump);
  ASSERT_EQ(buffer.lookup(1'100'000, &T, &jump), PoseBuffer::Lookup::kFound);
  EXPECT_EQ(T.translation().x(), 1.0);
  EXPECT_EQ(buffer.lookup(1'100'001, &T, &jump), PoseBuffer::Lookup::kNotYet);
  EXPECT_EQ(buffer.lookup(999'999, &T, &jump), PoseBuffer::Lookup::kTooOld);
}

// The reference keyframe comes with the pose: the exact pose's, or the nearer one's when
// interpolated (the later one at the midpoint); a caller that does not ask gets the pose.
TEST(PoseBufferTest, GivesTheReferenceKeyframeOfTheNearerPose) {
  PoseBuffer buffer(PoseBuffer::Config{});
  TimedPose a = poseAt(1'000'000, 0.0);
  a.reference_keyframe = 7;
  TimedPose b = poseAt(1'100'000, 1.0);
  b.reference_keyframe = 8;
  ASSERT_EQ(buffer.add(a), PoseBuffer::AddResult::kAdded);
  ASSERT_EQ(buffer.add(b), PoseBuffer::AddResult::kAdded);
  Transformationd T;
  bool jump = false;
  int64_t reference = -1;
  ASSERT_EQ(buffer.lookup(1'000'000, &T, &jump, &reference), PoseBuffer::Lookup::kFound);
  EXPECT_EQ(reference, 7);
  ASSERT_EQ(buffer.lookup(1'049'999, &T, &jump, &reference), PoseBuffer::Lookup::kFound);
  EXPECT_EQ(reference, 7);
  ASSERT_EQ(buffer.lookup(1'050'000, &T, &jump, &reference), PoseBuffer::Lookup::kFound);
  EXPECT_EQ(reference, 8);
  ASSERT_EQ(buffer.lookup(1'100'000, &T, &jump, &reference), PoseBuffer::Lookup::kFound);
  EXPECT_EQ(reference, 8);
  reference = 99;
  EXPECT_EQ(buffer.lookup(1'100'001, &T, &jump, &reference), PoseBuffer::Lookup::kNotYet);
  EXPECT_EQ(reference, 99);  // untouched unless found
  ASSERT_EQ(buffer.lookup(1'020'000, &T, &jump), PoseBuffer::Lookup::kFound);
}

TEST(PoseBufferTest, RefusesGapsJumpsLostPosesAndEpochChanges) {
  PoseBuffer::Config config;
  config.max_gap_s = 0.2;
  PoseBuffer buffer(config);
  buffer.add(poseAt(0, 0.0));
  buffer.add(poseAt(300'000, 1.0));                       // 0.3 s gap
  buffer.add(poseAt(400'000, 2.0, true, /*jump=*/true));  // relocalised
  buffer.add(poseAt(500'000, 2.1, /*ok=*/false));         // lost
  buffer.add(poseAt(600'000, 2.2));
  buffer.add(poseAt(700'000, 0.0, true, false, /*epoch=*/1));
  Transformationd T;
  bool jump = false;
  EXPECT_EQ(buffer.lookup(150'000, &T, &jump), PoseBuffer::Lookup::kGap);
  EXPECT_EQ(buffer.lookup(350'000, &T, &jump), PoseBuffer::Lookup::kAcrossJump);
  ASSERT_EQ(buffer.lookup(400'000, &T, &jump), PoseBuffer::Lookup::kFound);
  EXPECT_TRUE(jump);  // the jump frame itself is served and flagged
  EXPECT_EQ(buffer.lookup(450'000, &T, &jump), PoseBuffer::Lookup::kLost);
  EXPECT_EQ(buffer.lookup(500'000, &T, &jump), PoseBuffer::Lookup::kLost);
  EXPECT_EQ(buffer.lookup(650'000, &T, &jump), PoseBuffer::Lookup::kAcrossJump);  // epoch
}

TEST(PoseBufferTest, RejectsDuplicateOutOfOrderAndInvalidPosesAndForgetsOldOnes) {
  PoseBuffer::Config config;
  config.capacity = 3;
  PoseBuffer buffer(config);
  EXPECT_EQ(buffer.add(poseAt(10, 0.0)), PoseBuffer::AddResult::kAdded);
  EXPECT_EQ(buffer.add(poseAt(10, 0.0)), PoseBuffer::AddResult::kDuplicate);
  EXPECT_EQ(buffer.add(poseAt(5, 0.0)), PoseBuffer::AddResult::kOutOfOrder);
  TimedPose nan = poseAt(20, 0.0);
  nan.T_G_C =
      Transformationd(Eigen::Quaterniond::Identity(), Eigen::Vector3d(std::nan(""), 0.0, 0.0));
  EXPECT_EQ(buffer.add(nan), PoseBuffer::AddResult::kInvalid);
  for (int64_t t : {20, 30, 40}) buffer.add(poseAt(t, 0.0));
  EXPECT_EQ(buffer.size(), 3u);
  EXPECT_EQ(buffer.newestUtime(), 40);
  Transformationd T;
  bool jump;
  EXPECT_EQ(buffer.lookup(10, &T, &jump), PoseBuffer::Lookup::kTooOld);
  EXPECT_THROW(PoseBuffer(PoseBuffer::Config{-1.0, 10}), std::invalid_argument);
}

struct Frame {
  int64_t utime;
};

TEST(InTrayTest, NewestReadyFrameWinsAndOlderOnesAreDropped) {
  InTray<Frame> frames(8);
  for (int64_t t = 1; t <= 5; ++t) frames.push(Frame{t});
  // Poses known up to t = 3; t = 4, 5 wait; nothing is rejected.
  auto readiness = [](const Frame& f) {
    return f.utime <= 3 ? FrameReadiness::kReady : FrameReadiness::kWait;
  };
  const auto taken = frames.takeNewestReady(readiness);
  ASSERT_TRUE(taken.has_value());
  EXPECT_EQ(taken->utime, 3);
  EXPECT_EQ(frames.size(), 2u);  // 4 and 5 still wait
  InTrayCounters c = frames.counters();
  EXPECT_EQ(c.received, 5u);
  EXPECT_EQ(c.taken, 1u);
  EXPECT_EQ(c.dropped, 2u);  // 1 and 2 superseded
  EXPECT_FALSE(frames.takeNewestReady(readiness).has_value());
  // Frame 5 becomes ready: 4 is superseded.
  const auto next = frames.takeNewestReady([](const Frame&) { return FrameReadiness::kReady; });
  ASSERT_TRUE(next.has_value());
  EXPECT_EQ(next->utime, 5);
  EXPECT_EQ(frames.counters().dropped, 3u);
}

TEST(InTrayTest, RejectsUnservableFramesAndBoundsTheQueue) {
  InTray<Frame> frames(3);
  for (int64_t t = 1; t <= 5; ++t) frames.push(Frame{t});
  EXPECT_EQ(frames.size(), 3u);
  EXPECT_EQ(frames.counters().dropped, 2u);  // pushed out when full
  const auto taken = frames.takeNewestReady([](const Frame& f) {
    return f.utime == 5 ? FrameReadiness::kReject : FrameReadiness::kReady;
  });
  ASSERT_TRUE(taken.has_value());
  EXPECT_EQ(taken->utime, 4);
  EXPECT_EQ(frames.counters().rejected, 1u);
  EXPECT_EQ(frames.counters().dropped, 3u);  // 3 superseded by 4
  EXPECT_EQ(frames.size(), 0u);
}

TEST(InTrayTest, InOrderTheOldestReadyFrameComesFirstAndNothingIsSuperseded) {
  InTray<Frame> frames(4);
  for (int64_t t = 1; t <= 6; ++t) frames.push(Frame{t});
  EXPECT_EQ(frames.counters().dropped, 2u);  // 1 and 2 pushed out of the full tray
  const auto ready = [](const Frame&) { return FrameReadiness::kReady; };
  for (int64_t t = 3; t <= 4; ++t) {
    const auto taken = frames.takeOldestReady(ready);
    ASSERT_TRUE(taken.has_value());
    EXPECT_EQ(taken->utime, t);
  }
  EXPECT_EQ(frames.size(), 2u);
  EXPECT_EQ(frames.counters().dropped, 2u);  // none superseded
  // The oldest waits: nothing is served past it. Rejected frames before it are removed.
  frames.push(Frame{7});
  const auto wait5 = [](const Frame& f) {
    return f.utime == 5 ? FrameReadiness::kWait : FrameReadiness::kReady;
  };
  EXPECT_FALSE(frames.takeOldestReady(wait5).has_value());
  EXPECT_EQ(frames.size(), 3u);
  const auto reject5 = [](const Frame& f) {
    return f.utime == 5 ? FrameReadiness::kReject : FrameReadiness::kReady;
  };
  const auto six = frames.takeOldestReady(reject5);
  ASSERT_TRUE(six.has_value());
  EXPECT_EQ(six->utime, 6);
  const InTrayCounters c = frames.counters();
  EXPECT_EQ(c.received, 7u);
  EXPECT_EQ(c.taken, 3u);
  EXPECT_EQ(c.rejected, 1u);
  EXPECT_EQ(c.dropped, 2u);
  EXPECT_EQ(frames.takeOldestReady(ready)->utime, 7);
  EXPECT_FALSE(frames.takeOldestReady(ready).has_value());
}

TEST(InTrayTest, WaitForWorkWakesOnPushAndTimesOut) {
  InTray<Frame> frames(4);
  const auto start = std::chrono::steady_clock::now();
  frames.waitForWork(std::chrono::milliseconds(50));  // nothing pushed: times out
  EXPECT_GE(std::chrono::steady_clock::now() - start, std::chrono::milliseconds(45));
  std::thread producer([&] {
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
    frames.push(Frame{1});
  });
  frames.waitForWork(std::chrono::seconds(10));
  producer.join();
  EXPECT_EQ(frames.size(), 1u);
  EXPECT_LT(std::chrono::steady_clock::now() - start, std::chrono::seconds(5));
}

TEST(OutputPathTest, ConfinesPathsToTheOutputDirectory) {
  std::string error;
  EXPECT_EQ(*resolveOutputPath("/data/out", "map.ply", &error), "/data/out/map.ply");
  EXPECT_EQ(*resolveOutputPath("/data/out", "runs/./a/map.ply", &error),
            "/data/out/runs/a/map.ply");
  EXPECT_EQ(*resolveOutputPath("/data/out/", "/data/out/sub/m.ply", &error), "/data/out/sub/m.ply");
  EXPECT_EQ(*resolveOutputPath("out", "m.ply", &error), "out/m.ply");
  struct Case {
    const char* path;
    const char* why;
  };
  for (const Case& c : {Case{"", "is empty"}, Case{"../m.ply", "contains '..'"},
                        Case{"a/../../m.ply", "contains '..'"},
                        Case{"/etc/passwd", "is outside the output directory"},
                        Case{"/data/outside/m.ply", "is outside the output directory"}}) {
    EXPECT_FALSE(resolveOutputPath("/data/out", c.path, &error).has_value()) << c.path;
    EXPECT_NE(error.find(c.why), std::string::npos) << c.path << ": " << error;
  }
  EXPECT_FALSE(resolveOutputPath("/data/out", std::string("a\0b", 3), &error).has_value());
}

TEST(OutputPathTest, SymbolicLinksOutOfTheDirectoryAreCaught) {
  namespace fs = std::filesystem;
  const fs::path root = fs::temp_directory_path() / ("cblox_links_" + std::to_string(::getpid()));
  fs::remove_all(root);
  fs::create_directories(root / "out" / "sub");
  fs::create_directories(root / "elsewhere");
  fs::create_directory_symlink(root / "elsewhere", root / "out" / "escape");
  std::string error;
  // Lexically fine, but the link leads outside.
  const auto via_link = resolveOutputPath(root / "out", "escape/map.ply", &error);
  ASSERT_TRUE(via_link.has_value());
  EXPECT_FALSE(staysInsideOnDisk(root / "out", *via_link, &error));
  EXPECT_NE(error.find("leads outside the output directory"), std::string::npos) << error;
  // Real subdirectories and files not yet written are fine.
  EXPECT_TRUE(staysInsideOnDisk(root / "out", root / "out" / "sub" / "map.ply", &error)) << error;
  EXPECT_TRUE(staysInsideOnDisk(root / "out", root / "out" / "new" / "dir" / "m.ply", &error))
      << error;
  EXPECT_FALSE(staysInsideOnDisk(root / "missing", root / "missing" / "m.ply", &error));
  fs::remove_all(root);
}

TEST(MapEpochKeyTest, PacksEpochAndIdAndRefusesWhatDoesNotFit) {
  EXPECT_EQ(epochKey(0, 12), 12);  // epoch 0: the ids themselves
  EXPECT_EQ(epochKey(1, 0), int64_t{1} << 40);
  EXPECT_EQ(epochKey(3, 7), (int64_t{3} << 40) + 7);
  const int64_t key = *epochKey(kMaxMapEpoch, kMaxIdInEpoch);
  EXPECT_GT(key, 0);
  EXPECT_EQ(epochOfKey(key), kMaxMapEpoch);
  EXPECT_EQ(idOfKey(key), kMaxIdInEpoch);
  EXPECT_EQ(epochOfKey(*epochKey(5, 99)), 5);
  EXPECT_EQ(idOfKey(*epochKey(5, 99)), 99);
  EXPECT_FALSE(epochKey(-1, 0));
  EXPECT_FALSE(epochKey(0, -1));
  EXPECT_FALSE(epochKey(0, kMaxIdInEpoch + 1));
  EXPECT_FALSE(epochKey(kMaxMapEpoch + 1, 0));
}

}  // namespace
}  // namespace cblox
