#include "drivers/sim/sim_source.h"

#include <cmath>

#include <gtest/gtest.h>

#include "core/mesh/primitive_meshes.h"
#include "drivers/sim/builtin_scenes.h"

namespace cblox {
namespace {

SimSourceConfig smallConfig() {
  SimSourceConfig config;
  config.renderer.rig.stereo = PinholeIntrinsics{160.0, 160.0, 79.5, 59.5, 160, 120};
  config.renderer.rig.depth_max_m = 8.0;
  config.rate_hz = 10.0;
  return config;
}

std::shared_ptr<const TriangleMeshRaycaster> roomScene() {
  std::string error;
  std::shared_ptr<const TriangleMeshRaycaster> scene =
      TriangleMeshRaycaster::create(makeLivingRoom().mesh, &error);
  EXPECT_NE(scene, nullptr) << error;
  return scene;
}

TEST(SimSourceTest, DeliversFramesAtTheRateWithExactPosesAndConsistentDepth) {
  const auto scene = roomScene();
  const BuiltinScene room = makeLivingRoom();
  StampedTrajectory trajectory = makeSceneTrajectory(room, TrajectoryKind::kLoop, 50.0);
  ASSERT_GT(trajectory.back().timestamp_s, 2.0);
  SimSourceConfig config = smallConfig();
  config.max_frames = 12;
  SimSource source("sim:room/loop", scene, trajectory, config);
  EXPECT_EQ(source.frameCount(), 12u);
  EXPECT_TRUE(source.info().stereo.has_value());
  EXPECT_TRUE(source.info().has_ground_truth);
  EXPECT_EQ(source.info().depth_intrinsics->width, 160);

  CaptureFrame frame;
  std::string error;
  int count = 0;
  while (source.next(&frame, &error) == FrameSource::Status::kFrame) {
    EXPECT_EQ(frame.frame_id, count);
    EXPECT_EQ(frame.timestamp_ns, count * 100'000'000LL);
    ASSERT_TRUE(frame.T_G_C.has_value());
    // Frame k at 0.1 k s is trajectory sample 5 k (50 Hz).
    EXPECT_TRUE(frame.T_G_C->isApprox(trajectory[5 * count].T_G_C, 1e-9));
    ASSERT_EQ(frame.left.width, 160);
    ASSERT_EQ(frame.right.width, 160);
    ASSERT_EQ(frame.depth.width, 160);
    ASSERT_EQ(frame.color.width, 160);
    // Every depth pixel back-projects onto the true surface.
    const PinholeCamera camera(*source.info().depth_intrinsics);
    int valid = 0;
    double worst = 0.0;
    for (int v = 0; v < 120; v += 6) {
      for (int u = 0; u < 160; u += 6) {
        const float d = frame.depth(u, v);
        if (d <= 0.0f) continue;
        ++valid;
        const Eigen::Vector3d p_G = *frame.T_G_C * camera.backProject(Eigen::Vector2d(u, v), d);
        worst = std::max(worst, scene->closestPoint(p_G).distance);
      }
    }
    EXPECT_GT(valid, 400);
    EXPECT_LT(worst, 2e-5);
    ++count;
  }
  EXPECT_EQ(count, 12);
  EXPECT_EQ(source.next(&frame, &error), FrameSource::Status::kEnd);
}

TEST(SimSourceTest, DroppedFramesLeaveGapsInFrameIds) {
  SimSourceConfig config = smallConfig();
  config.noise.frame_drop_probability = 0.3;
  config.max_frames = 40;
  const BuiltinScene room = makeLivingRoom();
  SimSource source("sim", roomScene(), makeSceneTrajectory(room, TrajectoryKind::kOrbit, 10.0),
                   config);
  CaptureFrame frame;
  std::string error;
  int delivered = 0;
  int64_t last = -1;
  bool gap = false;
  while (source.next(&frame, &error) == FrameSource::Status::kFrame) {
    EXPECT_GT(frame.frame_id, last);
    gap |= frame.frame_id > last + 1;
    last = frame.frame_id;
    EXPECT_EQ(frame.timestamp_ns, frame.frame_id * 100'000'000LL);
    ++delivered;
  }
  EXPECT_TRUE(gap);
  EXPECT_LT(delivered, 40);
  EXPECT_GT(delivered, 15);
}

TEST(SimSourceTest, MotionBlurSmoothsImagesOfAFastCamera) {
  auto gradient_energy = [](const GrayImage& image) {
    double sum = 0.0;
    for (int v = 0; v < image.height; ++v) {
      for (int u = 1; u < image.width; ++u) {
        const double g = image(u, v) - image(u - 1, v);
        sum += g * g;
      }
    }
    return sum;
  };
  const BuiltinScene room = makeLivingRoom();
  StampedTrajectory trajectory = makeSceneTrajectory(room, TrajectoryKind::kOrbit, 10.0);
  SimSourceConfig sharp = smallConfig();
  sharp.rate_hz = 1.0;
  sharp.max_frames = 4;
  SimSourceConfig blurred = sharp;
  blurred.noise.exposure_time_s = 0.4;  // long exposure while orbiting
  blurred.noise.blur_samples = 8;
  SimSource a("a", roomScene(), trajectory, sharp), b("b", roomScene(), trajectory, blurred);
  CaptureFrame fa, fb;
  std::string error;
  for (int i = 0; i < 4; ++i) {
    ASSERT_EQ(a.next(&fa, &error), FrameSource::Status::kFrame);
    ASSERT_EQ(b.next(&fb, &error), FrameSource::Status::kFrame);
  }
  EXPECT_LT(gradient_energy(fb.left), 0.8 * gradient_energy(fa.left));
  EXPECT_EQ(fa.depth.data, fb.depth.data);  // depth is not blurred
}

TEST(SimSourceTest, RejectsBadArguments) {
  EXPECT_THROW(SimSource("x", roomScene(), {}, smallConfig()), std::invalid_argument);
  SimSourceConfig config = smallConfig();
  config.rate_hz = 0.0;
  EXPECT_THROW(SimSource("x", roomScene(), {{0.0, Transformationd()}}, config),
               std::invalid_argument);
}

}  // namespace
}  // namespace cblox
