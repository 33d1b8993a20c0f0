#include "core/optimization/pose_optimizer.h"

#include <random>
#include <stdexcept>

#include <gtest/gtest.h>

#include "test/optimization/synthetic_scenes.h"

namespace cblox {
namespace {

struct PoseRun {
  Transformationd start;
  PoseOptimizationResult result;
};

// optimizePose from the true pose perturbed by (sigma_t metres, sigma_r radians).
PoseRun optimizeFromPerturbation(const test::PoseScene& scene, double sigma_t, double sigma_r,
                                 std::uint32_t seed) {
  std::mt19937 rng(seed);
  PoseRun run;
  run.start = test::perturbPose(scene.T_C_G_true, sigma_t, sigma_r, rng);
  run.result = optimizePose(test::syntheticCamera(), run.start, scene.observations);
  return run;
}

TEST(PoseOptimizer, RecoversTheExactPoseFromAPerturbation) {
  const test::PoseScene scene = test::makePoseScene(300, 0.0, 21);
  const PoseOptimizationResult result = optimizeFromPerturbation(scene, 0.05, 0.05, 22).result;
  EXPECT_LT(test::poseDistance(result.T_C_G, scene.T_C_G_true), 1e-9);
  EXPECT_EQ(result.num_inliers, 300);
  ASSERT_EQ(result.inlier.size(), 300u);
  for (std::uint8_t f : result.inlier) EXPECT_EQ(f, 1);
  EXPECT_LT(result.final_chi2, 1e-12);
  EXPECT_GT(result.initial_chi2, 100.0);
  EXPECT_GE(result.iterations, 4);
  EXPECT_LE(result.iterations, 40);
}

TEST(PoseOptimizer, FlagsInjectedOutliersAndIgnoresThem) {
  test::PoseScene scene = test::makePoseScene(300, 0.0, 31);
  std::mt19937 rng(32);
  std::uniform_real_distribution<double> offset(20.0, 60.0);
  std::vector<std::uint8_t> injected(scene.observations.size(), 0);
  for (size_t i = 0; i < scene.observations.size(); i += 5) {  // 20% gross outliers
    scene.observations[i].u += (i % 2 ? 1 : -1) * offset(rng);
    scene.observations[i].v += offset(rng);
    injected[i] = 1;
  }
  const PoseOptimizationResult result = optimizeFromPerturbation(scene, 0.03, 0.02, 33).result;
  for (size_t i = 0; i < injected.size(); ++i) {
    EXPECT_EQ(result.inlier[i], injected[i] ? 0 : 1) << "observation " << i;
  }
  EXPECT_EQ(result.num_inliers, 240);
  // The last round has no robust kernel and no outliers: exact again.
  EXPECT_LT(test::poseDistance(result.T_C_G, scene.T_C_G_true), 1e-9);
}

TEST(PoseOptimizer, NoisyObservationsGiveAConsistentChi2) {
  const test::PoseScene scene = test::makePoseScene(300, 1.0, 41);
  const PoseRun run = optimizeFromPerturbation(scene, 0.05, 0.03, 42);
  const PoseOptimizationResult& result = run.result;
  EXPECT_LT(test::poseDistance(result.T_C_G, scene.T_C_G_true), 0.01);
  EXPECT_LT(test::poseDistance(result.T_C_G, scene.T_C_G_true),
            0.2 * test::poseDistance(run.start, scene.T_C_G_true));
  // 95% thresholds: about 5% of clean observations are classified outliers.
  EXPECT_GE(result.num_inliers, 270);
  EXPECT_LE(result.num_inliers, 297);
  int dims = 0;
  for (size_t i = 0; i < scene.observations.size(); ++i) {
    if (result.inlier[i]) dims += scene.observations[i].dimension();
  }
  // chi2 of the truncated inliers per residual dimension: below 1 (the tail is cut), but not
  // much below.
  EXPECT_GT(result.final_chi2 / dims, 0.6);
  EXPECT_LT(result.final_chi2 / dims, 1.0);
}

TEST(PoseOptimizer, PointsBehindTheCameraAreOutliers) {
  test::PoseScene scene = test::makePoseScene(100, 0.0, 51);
  const Transformationd T_G_C = scene.T_C_G_true.inverse();
  scene.observations[7].p_G = T_G_C * Eigen::Vector3d(0.5, 0.2, -3.0);
  scene.observations[8].p_G = T_G_C * Eigen::Vector3d(0.0, 0.0, 0.0);
  const PoseOptimizationResult result =
      optimizePose(test::syntheticCamera(), scene.T_C_G_true, scene.observations);
  EXPECT_EQ(result.inlier[7], 0);
  EXPECT_EQ(result.inlier[8], 0);
  EXPECT_EQ(result.num_inliers, 98);
  EXPECT_LT(test::poseDistance(result.T_C_G, scene.T_C_G_true), 1e-12);
}

TEST(PoseOptimizer, RejectsInvalidInputWithAClearMessage) {
  const test::PoseScene scene = test::makePoseScene(20, 0.0, 61);
  const StereoCameraModel cam = test::syntheticCamera();
  const auto message = [&](const StereoCameraModel& c, std::span<const PoseObservation> obs,
                           const PoseOptimizerConfig& config) -> std::string {
    try {
      optimizePose(c, scene.T_C_G_true, obs, config);
    } catch (const std::invalid_argument& e) {
      return e.what();
    }
    return "no exception";
  };
  EXPECT_EQ(message(cam, {}, {}), "optimizePose: no observations");
  std::vector<PoseObservation> bad = scene.observations;
  bad[3].p_G.x() = std::nan("");
  EXPECT_EQ(message(cam, bad, {}), "optimizePose: observation 3: p_G must be finite");
  bad = scene.observations;
  bad[4].inv_sigma2 = 0.0;
  EXPECT_EQ(message(cam, bad, {}),
            "optimizePose: observation 4: inv_sigma2 must be > 0 and finite");
  bad = scene.observations;
  bad[5].u_right = std::nan("");
  EXPECT_EQ(message(cam, bad, {}), "optimizePose: observation 5: u, v and u_right must be finite");
  StereoCameraModel bad_cam = cam;
  bad_cam.bf = -1.0;
  EXPECT_EQ(message(bad_cam, scene.observations, {}),
            "optimizePose: camera: bf must be > 0 and finite, got -1");
  PoseOptimizerConfig config;
  config.robust_rounds = 5;
  EXPECT_EQ(message(cam, scene.observations, config),
            "optimizePose: config: robust_rounds must be in [0, rounds]");
  EXPECT_EQ(validate(PoseOptimizerConfig{}), "");
}

}  // namespace
}  // namespace cblox
