#include "core/optimization/disparity_offset.h"

#include <gtest/gtest.h>

#include "test/optimization/synthetic_scenes.h"

namespace cblox {
namespace {

// A window of 10 keyframes over points 2-9 m away, keyframe 0 fixed, every right-image
// measurement taken by a right camera whose principal point is `offset_px` right of the
// calibration's.
test::BaScene sceneWithOffset(double offset_px, double pixel_noise, std::uint32_t seed) {
  test::BaSceneOptions options;
  options.pixel_noise = pixel_noise;
  options.seed = seed;
  test::BaScene scene = test::makeBaScene(options);
  scene.problem.keyframes[0].fixed = true;
  for (BaObservation& o : scene.problem.observations) {
    if (o.u_right >= 0.0) o.u_right += offset_px;
  }
  test::perturbInitialState(&scene, 0.02, 0.005, 0.05, seed + 7);
  return scene;
}

TEST(DisparityOffsetTest, ExactMeasurementsGiveTheOffsetExactly) {
  for (const double offset : {1.4, -0.7, 0.0}) {
    const test::BaScene scene = sceneWithOffset(offset, 0.0, 3);
    const DisparityOffsetEstimate e =
        estimateDisparityOffset(scene.problem, DisparityOffsetSolverConfig{});
    ASSERT_TRUE(e.ok) << e.reason;
    EXPECT_NEAR(e.offset_px, offset, 1e-4) << offset;
    EXPECT_EQ(e.landmarks, 500);
    EXPECT_GE(e.stereo_observations, 200);
    EXPECT_LT(e.final_cost, 1e-6 * e.initial_cost);
  }
}

TEST(DisparityOffsetTest, NoisyMeasurementsGiveTheOffsetWithinAFewTenthsOfAPixel) {
  // Half a pixel of noise (times the octave's scale) on every coordinate, disparities of
  // 5-25 px: one window's estimate is within 0.01-0.12 px here (three seeds), which is why
  // the tracker combines the estimates of many windows.
  for (std::uint32_t seed = 1; seed <= 3; ++seed) {
    const test::BaScene scene = sceneWithOffset(1.4, 0.5, seed);
    const DisparityOffsetEstimate e =
        estimateDisparityOffset(scene.problem, DisparityOffsetSolverConfig{});
    ASSERT_TRUE(e.ok) << e.reason;
    EXPECT_NEAR(e.offset_px, 1.4, 0.15) << "seed " << seed;
  }
}

TEST(DisparityOffsetTest, RefusesWhatCannotDetermineIt) {
  test::BaScene scene = sceneWithOffset(1.0, 0.0, 5);
  DisparityOffsetSolverConfig config;
  config.min_stereo_observations = 1000000;
  DisparityOffsetEstimate e = estimateDisparityOffset(scene.problem, config);
  EXPECT_FALSE(e.ok);
  EXPECT_NE(e.reason.find("stereo observations"), std::string::npos) << e.reason;
  config = DisparityOffsetSolverConfig{};
  config.max_landmarks = 0;
  e = estimateDisparityOffset(scene.problem, config);
  EXPECT_FALSE(e.ok);
  EXPECT_NE(e.reason.find("max_landmarks"), std::string::npos) << e.reason;
  scene.problem.keyframes[0].fixed = false;
  e = estimateDisparityOffset(scene.problem, DisparityOffsetSolverConfig{});
  EXPECT_FALSE(e.ok);
  EXPECT_NE(e.reason.find("fixed"), std::string::npos) << e.reason;
  scene.problem.observations[0].keyframe = 99;
  e = estimateDisparityOffset(scene.problem, DisparityOffsetSolverConfig{});
  EXPECT_FALSE(e.ok);
  EXPECT_NE(e.reason.find("problem"), std::string::npos) << e.reason;
}

}  // namespace
}  // namespace cblox
