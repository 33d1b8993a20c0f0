#include "core/optimization/bundle_adjustment.h"

#include <random>
#include <stdexcept>

#include <gtest/gtest.h>

#include "test/covariance/loop_scene.h"
#include "test/optimization/synthetic_scenes.h"

namespace cblox {
namespace {

// Tolerances tight enough that the noiseless problem converges to rounding.
BundleAdjustmentConfig tightConfig() {
  BundleAdjustmentConfig config;
  config.second_pass_iterations = 30;
  config.solver.function_tolerance = 1e-16;
  config.solver.gradient_tolerance = 1e-16;
  config.solver.parameter_tolerance = 1e-14;
  return config;
}

double maxPoseError(const BundleAdjustmentResult& r, const test::BaScene& s) {
  double e = 0.0;
  for (size_t k = 0; k < s.T_C_G_true.size(); ++k) {
    e = std::max(e, test::poseDistance(r.T_C_G[k], s.T_C_G_true[k]));
  }
  return e;
}

double maxPointError(const std::vector<Eigen::Vector3d>& p, const test::BaScene& s) {
  double e = 0.0;
  for (size_t l = 0; l < s.p_G_true.size(); ++l) e = std::max(e, (p[l] - s.p_G_true[l]).norm());
  return e;
}

std::vector<Eigen::Vector3d> points(const BundleAdjustmentProblem& p) {
  std::vector<Eigen::Vector3d> out;
  for (const BaLandmark& l : p.landmarks) out.push_back(l.p_G);
  return out;
}

test::BaScene perturbedScene(double pixel_noise, std::uint32_t seed) {
  test::BaSceneOptions options;
  options.pixel_noise = pixel_noise;
  options.seed = seed;
  return test::makeGaugedPerturbedBaScene(options, 0.02, 0.01, 0.05);
}

TEST(BundleAdjustment, NoiselessObservationsRecoverTheTruth) {
  const test::BaScene scene = perturbedScene(0.0, 101);
  ASSERT_EQ(scene.problem.landmarks.size(), 500u);
  ASSERT_GT(scene.problem.observations.size(), 2500u);
  BundleAdjustmentConfig config = tightConfig();
  config.native_max_free_keyframes = 0;  // kAuto picks Ceres
  config.native_sparse = false;
  const BundleAdjustmentResult r = bundleAdjust(scene.problem, config);
  ASSERT_TRUE(r.success) << r.message;
  EXPECT_LT(maxPoseError(r, scene), 1e-6);
  EXPECT_LT(maxPointError(r.p_G, scene), 1e-6);
  EXPECT_EQ(r.num_outliers, 0);
  EXPECT_GT(r.initial_cost, 1e3);
  EXPECT_LT(r.final_cost, 1e-12);
  EXPECT_LT(r.final_chi2, 1e-12);
  EXPECT_EQ(r.linear_solver, "DENSE_SCHUR");
  // The fixed gauge keyframe is returned exactly as given.
  EXPECT_EQ(r.T_C_G[0].rotation().coeffs(), scene.problem.keyframes[0].T_C_G.rotation().coeffs());
  EXPECT_EQ(r.T_C_G[0].translation(), scene.problem.keyframes[0].T_C_G.translation());
}

double rmsPoseError(const std::vector<Transformationd>& T, const test::BaScene& s) {
  double sum = 0.0;
  for (size_t k = 0; k < T.size(); ++k)
    sum += std::pow(test::poseDistance(T[k], s.T_C_G_true[k]), 2);
  return std::sqrt(sum / T.size());
}

double rmsPointError(const std::vector<Eigen::Vector3d>& p, const test::BaScene& s) {
  double sum = 0.0;
  for (size_t l = 0; l < p.size(); ++l) sum += (p[l] - s.p_G_true[l]).squaredNorm();
  return std::sqrt(sum / p.size());
}

TEST(BundleAdjustment, PixelNoiseImprovesOnTheStartWithConsistentChi2) {
  test::BaSceneOptions options;
  options.pixel_noise = 1.0;
  options.seed = 201;
  const test::BaScene scene = test::makeGaugedPerturbedBaScene(options, 0.05, 0.02, 0.2);
  const BundleAdjustmentResult r = bundleAdjust(scene.problem);  // ORB-SLAM2 defaults
  ASSERT_TRUE(r.success) << r.message;
  std::vector<Transformationd> start;
  for (const BaKeyframe& kf : scene.problem.keyframes) start.push_back(kf.T_C_G);
  // (The remaining ~1 cm is what 1-1.7 px noise with an 11 cm baseline allows: see
  // BaLinearization.PredictedCovarianceIsConsistentWithTheActualPoseErrors.)
  EXPECT_LT(rmsPoseError(r.T_C_G, scene), 0.3 * rmsPoseError(start, scene));
  EXPECT_LT(rmsPointError(r.p_G, scene), 0.5 * rmsPointError(points(scene.problem), scene));
  const auto n = static_cast<int>(scene.problem.observations.size());
  // 95% thresholds: ~5% of clean observations are classified outliers.
  EXPECT_GT(r.num_outliers, n / 50);
  EXPECT_LT(r.num_outliers, n / 10);
  int dims = 0;
  for (int i = 0; i < n; ++i) {
    if (!r.outlier[i]) dims += scene.problem.observations[i].dimension();
  }
  EXPECT_GT(r.final_chi2 / dims, 0.6);
  EXPECT_LT(r.final_chi2 / dims, 1.0);
  EXPECT_GE(r.iterations, 3);
  EXPECT_LE(r.iterations, 15);
  EXPECT_GT(r.time_ms, 0.0);
}

TEST(BundleAdjustment, GrossOutliersAreFlaggedAndDoNotBiasTheResult) {
  test::BaScene scene = perturbedScene(0.0, 301);
  std::vector<std::uint8_t> injected(scene.problem.observations.size(), 0);
  for (size_t i = 3; i < injected.size(); i += 20) {  // 5% outliers, 25-40 px off
    scene.problem.observations[i].u += (i % 3 ? 25.0 : -40.0);
    scene.problem.observations[i].v += 30.0;
    injected[i] = 1;
  }
  const BundleAdjustmentResult r = bundleAdjust(scene.problem, tightConfig());
  ASSERT_TRUE(r.success) << r.message;
  for (size_t i = 0; i < injected.size(); ++i) {
    EXPECT_EQ(r.outlier[i], injected[i]) << "observation " << i;
  }
  EXPECT_LT(maxPoseError(r, scene), 1e-6);
  EXPECT_LT(maxPointError(r.p_G, scene), 1e-6);
}

TEST(BundleAdjustment, AllLinearSolversAgree) {
  const test::BaScene scene = perturbedScene(0.5, 401);
  BundleAdjustmentConfig config = tightConfig();
  config.linear_solver = BaLinearSolver::kDenseSchur;
  const BundleAdjustmentResult dense = bundleAdjust(scene.problem, config);
  config.linear_solver = BaLinearSolver::kSparseSchur;
  const BundleAdjustmentResult sparse = bundleAdjust(scene.problem, config);
  config.linear_solver = BaLinearSolver::kIterativeSchur;
  const BundleAdjustmentResult iterative = bundleAdjust(scene.problem, config);
  EXPECT_EQ(dense.linear_solver, "DENSE_SCHUR");
  EXPECT_EQ(sparse.linear_solver, "SPARSE_SCHUR");
  EXPECT_EQ(iterative.linear_solver, "ITERATIVE_SCHUR");
  for (size_t k = 0; k < scene.T_C_G_true.size(); ++k) {
    EXPECT_LT(test::poseDistance(dense.T_C_G[k], sparse.T_C_G[k]), 1e-8);
    EXPECT_LT(test::poseDistance(dense.T_C_G[k], iterative.T_C_G[k]), 1e-6);
  }
  EXPECT_EQ(dense.outlier, sparse.outlier);
}

TEST(BundleAdjustment, GlobalPresetWithOnlyTheGaugeFixed) {
  const BundleAdjustmentConfig g = globalBundleAdjustmentConfig();
  EXPECT_EQ(g.first_pass_iterations, 10);
  EXPECT_EQ(g.second_pass_iterations, 0);
  EXPECT_EQ(validate(g), "");
  test::BaSceneOptions options;
  options.keyframes = 12;
  options.landmarks = 300;
  options.seed = 501;
  test::BaScene scene = test::makeBaScene(options);
  scene.problem.keyframes[0].fixed = true;
  test::perturbInitialState(&scene, 0.01, 0.005, 0.02, 502);
  const BundleAdjustmentResult r = bundleAdjust(scene.problem, g);
  ASSERT_TRUE(r.success);
  EXPECT_LT(maxPoseError(r, scene), 1e-5);
  EXPECT_EQ(r.num_outliers, 0);
}

TEST(BundleAdjustment, AbortStopsAfterTheFirstIterationAndSkipsPassTwo) {
  const test::BaScene scene = perturbedScene(0.0, 601);
  const std::atomic<bool> abort{true};
  const BundleAdjustmentResult r = bundleAdjust(scene.problem, {}, &abort);
  EXPECT_TRUE(r.aborted);
  EXPECT_TRUE(r.success);
  EXPECT_LE(r.iterations, 1);
  const std::atomic<bool> keep_going{false};
  EXPECT_FALSE(bundleAdjust(scene.problem, {}, &keep_going).aborted);
}

TEST(BundleAdjustment, TimeLimitEndsEarlyWithAUsableResult) {
  const test::BaScene scene = perturbedScene(0.0, 651);
  BundleAdjustmentConfig config;
  config.solver.max_time_s = 1e-6;
  const BundleAdjustmentResult r = bundleAdjust(scene.problem, config);
  EXPECT_TRUE(r.success) << r.message;
  EXPECT_LE(r.iterations, 1);  // Ceres checks the limit after each iteration; no pass 2
  EXPECT_EQ(r.outlier.size(), scene.problem.observations.size());
}

TEST(BundleAdjustment, PointsBehindTheInitialCameraAreOutliers) {
  test::BaScene scene = perturbedScene(0.0, 701);
  // Move landmark 0 behind keyframe 3 (and every other camera): its observations cannot be
  // evaluated at the start and are excluded.
  const Eigen::Vector3d behind = scene.T_C_G_true[3].inverse() * Eigen::Vector3d(0, 0, -5);
  scene.problem.landmarks[0].p_G = behind;
  const BundleAdjustmentResult r = bundleAdjust(scene.problem);
  ASSERT_TRUE(r.success) << r.message;
  for (size_t i = 0; i < scene.problem.observations.size(); ++i) {
    if (scene.problem.observations[i].landmark == 0) {
      EXPECT_EQ(r.outlier[i], 1);
    }
  }
  EXPECT_EQ(r.p_G[0], behind);  // no usable observation: unchanged
}

std::string errorOf(const BundleAdjustmentProblem& p, const BundleAdjustmentConfig& c = {}) {
  try {
    bundleAdjust(p, c);
  } catch (const std::invalid_argument& e) {
    return e.what();
  }
  return "no exception";
}

TEST(BundleAdjustment, RejectsInvalidInputWithAClearMessage) {
  test::BaSceneOptions options;
  options.keyframes = 3;
  options.landmarks = 10;
  const test::BaScene scene = test::makeBaScene(options);
  EXPECT_EQ(validate(scene.problem), "");
  EXPECT_EQ(errorOf(BundleAdjustmentProblem{scene.problem.camera, {}, {}, {}}),
            "bundleAdjust: no keyframes");
  BundleAdjustmentProblem p = scene.problem;
  p.observations.clear();
  EXPECT_EQ(errorOf(p), "bundleAdjust: no observations");
  p = scene.problem;
  p.observations[2].keyframe = 3;
  EXPECT_EQ(errorOf(p), "bundleAdjust: observation 2: keyframe index 3 out of range [0, 3)");
  p = scene.problem;
  p.observations[4].landmark = -1;
  EXPECT_EQ(errorOf(p), "bundleAdjust: observation 4: landmark index -1 out of range [0, 10)");
  p = scene.problem;
  p.observations[5].v = std::nan("");
  EXPECT_EQ(errorOf(p), "bundleAdjust: observation 5: u, v and u_right must be finite");
  p = scene.problem;
  p.landmarks[6].p_G.z() = HUGE_VAL;
  EXPECT_EQ(errorOf(p), "bundleAdjust: landmark 6: p_G not finite");
  p = scene.problem;
  p.keyframes[1].T_C_G =
      Transformationd(Eigen::Quaterniond::Identity(), Eigen::Vector3d(std::nan(""), 0, 0));
  EXPECT_EQ(errorOf(p), "bundleAdjust: keyframe 1: T_C_G not finite");
  p = scene.problem;
  p.camera.fy = 0.0;
  EXPECT_EQ(errorOf(p), "bundleAdjust: camera: fy must be > 0 and finite, got 0");
  BundleAdjustmentConfig config;
  config.solver.num_threads = 0;
  EXPECT_EQ(errorOf(scene.problem, config),
            "bundleAdjust: config: solver: num_threads must be >= 1");
  config = {};
  config.solver.max_time_s = -1.0;
  EXPECT_EQ(errorOf(scene.problem, config),
            "bundleAdjust: config: solver: max_time_s must be >= 0 and finite");
}


// Our own Schur-complement Levenberg-Marquardt (schur_lm.h) against Ceres' DENSE_SCHUR.
BundleAdjustmentConfig nativeConfig(BundleAdjustmentConfig config = {}) {
  config.linear_solver = BaLinearSolver::kNativeDenseSchur;
  return config;
}

TEST(BundleAdjustmentNative, NoiselessObservationsRecoverTheTruth) {
  const test::BaScene scene = perturbedScene(0.0, 101);
  const BundleAdjustmentResult r = bundleAdjust(scene.problem, nativeConfig(tightConfig()));
  ASSERT_TRUE(r.success) << r.message;
  EXPECT_EQ(r.linear_solver, "NATIVE_DENSE_SCHUR");
  EXPECT_LT(maxPoseError(r, scene), 1e-6);
  EXPECT_LT(maxPointError(r.p_G, scene), 1e-6);
  EXPECT_EQ(r.num_outliers, 0);
  EXPECT_GT(r.initial_cost, 1e3);
  EXPECT_LT(r.final_cost, 1e-12);
  EXPECT_EQ(r.T_C_G[0].rotation().coeffs(), scene.problem.keyframes[0].T_C_G.rotation().coeffs());
  EXPECT_EQ(r.T_C_G[0].translation(), scene.problem.keyframes[0].T_C_G.translation());
}

TEST(BundleAdjustmentNative, ConvergesToCeresSolution) {
  const test::BaScene scene = perturbedScene(0.5, 401);
  BundleAdjustmentConfig config = tightConfig();
  config.linear_solver = BaLinearSolver::kDenseSchur;
  const BundleAdjustmentResult ceres = bundleAdjust(scene.problem, config);
  const BundleAdjustmentResult native = bundleAdjust(scene.problem, nativeConfig(config));
  ASSERT_TRUE(native.success);
  // The same cost: the same initial cost exactly (to rounding), the same minimum.
  EXPECT_NEAR(native.initial_cost, ceres.initial_cost, 1e-9 * ceres.initial_cost);
  EXPECT_NEAR(native.final_chi2, ceres.final_chi2, 1e-7 * ceres.final_chi2);
  EXPECT_EQ(native.outlier, ceres.outlier);
  for (size_t k = 0; k < scene.T_C_G_true.size(); ++k) {
    EXPECT_LT(test::poseDistance(native.T_C_G[k], ceres.T_C_G[k]), 1e-7) << k;
  }
  EXPECT_LT(maxPointError(native.p_G, scene) - maxPointError(ceres.p_G, scene), 1e-7);
}

TEST(BundleAdjustmentNative, OrbSlamScheduleMatchesCeresWithOutliers) {
  // ORB-SLAM2's 5 + 10 iterations, 1 px noise and 3% gross outliers: both stop short of the
  // minimum, so they agree on the outliers and nearly on the cost.
  test::BaSceneOptions options;
  options.pixel_noise = 1.0;
  options.seed = 211;
  test::BaScene scene = test::makeGaugedPerturbedBaScene(options, 0.05, 0.02, 0.2);
  for (size_t i = 0; i < scene.problem.observations.size(); i += 33) {
    scene.problem.observations[i].u += 35.0;
  }
  BundleAdjustmentConfig config;
  config.linear_solver = BaLinearSolver::kDenseSchur;
  const BundleAdjustmentResult ceres = bundleAdjust(scene.problem, config);
  const BundleAdjustmentResult native = bundleAdjust(scene.problem, nativeConfig());
  ASSERT_TRUE(native.success);
  EXPECT_LE(native.iterations, 15);
  EXPECT_NEAR(native.final_chi2, ceres.final_chi2, 0.01 * ceres.final_chi2);
  size_t differ = 0;
  for (size_t i = 0; i < native.outlier.size(); ++i) differ += native.outlier[i] != ceres.outlier[i];
  EXPECT_LE(differ, native.outlier.size() / 200);
  for (size_t i = 0; i < scene.problem.observations.size(); i += 33) EXPECT_EQ(native.outlier[i], 1);
  EXPECT_LT(rmsPoseError(native.T_C_G, scene), 1.05 * rmsPoseError(ceres.T_C_G, scene));
}

TEST(BundleAdjustmentNative, AbortAndTimeLimitStopBeforeTheFirstStep) {
  const test::BaScene scene = perturbedScene(0.0, 601);
  const std::atomic<bool> abort{true};
  BundleAdjustmentResult r = bundleAdjust(scene.problem, nativeConfig(), &abort);
  EXPECT_TRUE(r.aborted);
  EXPECT_TRUE(r.success);
  EXPECT_EQ(r.iterations, 0);
  for (size_t k = 0; k < scene.problem.keyframes.size(); ++k) {
    EXPECT_EQ(r.T_C_G[k].translation(), scene.problem.keyframes[k].T_C_G.translation());
  }
  BundleAdjustmentConfig config = nativeConfig();
  config.solver.max_time_s = 1e-9;
  r = bundleAdjust(scene.problem, config);
  EXPECT_FALSE(r.aborted);
  EXPECT_EQ(r.iterations, 0);
  EXPECT_EQ(r.outlier.size(), scene.problem.observations.size());
}

TEST(BundleAdjustmentNative, GrossOutliersAndPointsBehindTheCamera) {
  test::BaScene scene = perturbedScene(0.0, 301);
  std::vector<std::uint8_t> injected(scene.problem.observations.size(), 0);
  for (size_t i = 3; i < injected.size(); i += 20) {
    scene.problem.observations[i].u += (i % 3 ? 25.0 : -40.0);
    scene.problem.observations[i].v += 30.0;
    injected[i] = 1;
  }
  const Eigen::Vector3d behind = scene.T_C_G_true[3].inverse() * Eigen::Vector3d(0, 0, -5);
  scene.problem.landmarks[0].p_G = behind;
  const BundleAdjustmentResult r = bundleAdjust(scene.problem, nativeConfig(tightConfig()));
  ASSERT_TRUE(r.success);
  for (size_t i = 0; i < injected.size(); ++i) {
    const bool of_landmark_0 = scene.problem.observations[i].landmark == 0;
    EXPECT_EQ(r.outlier[i], of_landmark_0 ? 1 : injected[i]) << "observation " << i;
  }
  EXPECT_EQ(r.p_G[0], behind);  // no usable observation: unchanged
  EXPECT_LT(maxPoseError(r, scene), 1e-6);
}

TEST(BundleAdjustmentNative, AutoUsesItUpToItsFreeKeyframeLimit) {
  const test::BaScene scene = perturbedScene(0.5, 411);  // 1 fixed keyframe, the rest free
  int free = 0;
  for (const BaKeyframe& k : scene.problem.keyframes) free += k.fixed ? 0 : 1;
  BundleAdjustmentConfig config;
  EXPECT_EQ(config.native_max_free_keyframes, 80);
  EXPECT_TRUE(config.native_sparse);
  EXPECT_EQ(bundleAdjust(scene.problem, config).linear_solver, "NATIVE_DENSE_SCHUR");
  config.native_max_free_keyframes = 0;
  EXPECT_EQ(bundleAdjust(scene.problem, config).linear_solver, "NATIVE_SPARSE_SCHUR");
  config.native_max_free_keyframes = free;
  EXPECT_EQ(bundleAdjust(scene.problem, config).linear_solver, "NATIVE_DENSE_SCHUR");
  config.native_max_free_keyframes = free - 1;
  EXPECT_EQ(bundleAdjust(scene.problem, config).linear_solver, "NATIVE_SPARSE_SCHUR");
  config.native_sparse = false;  // Ceres above the limit
  EXPECT_EQ(bundleAdjust(scene.problem, config).linear_solver, "DENSE_SCHUR");
  config.native_max_free_keyframes = -1;
  EXPECT_EQ(validate(config), "native_max_free_keyframes must be >= 0");
}

// The sparse reduced matrix (CHOLMOD) changes only how each step's linear system is solved:
// the same steps, iterations, outliers and solution as the dense one, to rounding.
TEST(BundleAdjustmentNative, SparseReducedMatrixTakesTheDenseOnesSteps) {
  test::BaScene scene = perturbedScene(1.0, 421);
  for (size_t i = 0; i < scene.problem.observations.size(); i += 40) {
    scene.problem.observations[i].v += 30.0;
  }
  BundleAdjustmentConfig config;
  config.linear_solver = BaLinearSolver::kNativeSparseSchur;
  const BundleAdjustmentResult sparse = bundleAdjust(scene.problem, config);
  const BundleAdjustmentResult dense = bundleAdjust(scene.problem, nativeConfig());
  EXPECT_EQ(sparse.linear_solver, "NATIVE_SPARSE_SCHUR");
  EXPECT_EQ(sparse.iterations, dense.iterations);
  EXPECT_EQ(sparse.outlier, dense.outlier);
  EXPECT_GT(sparse.num_outliers, 0);
  EXPECT_NEAR(sparse.final_chi2, dense.final_chi2, 1e-9 * dense.final_chi2);
  for (size_t k = 0; k < scene.T_C_G_true.size(); ++k) {
    EXPECT_LT(test::poseDistance(sparse.T_C_G[k], dense.T_C_G[k]), 1e-9) << k;
  }
}

// A whole-map BA: a closed two-lap loop of 200 keyframes (keyframe 0 fixed, 10,000 landmarks,
// loop edges in the reduced matrix), noisy, started away from the solution. Ours with the
// sparse reduced matrix reaches Ceres' SPARSE_SCHUR minimum; kAuto takes it above
// native_max_free_keyframes when native_sparse is set.
TEST(BundleAdjustmentNative, SparseReducedMatrixReachesCeresMinimumOnALoop) {
  test::LoopSceneOptions options;
  options.keyframes = 200;
  options.seed = 7;
  test::BaScene scene = test::makeLoopBaScene(options);
  std::mt19937 rng(8);
  std::normal_distribution<double> pixel(0.0, 0.5);
  for (BaObservation& o : scene.problem.observations) {
    const double du = pixel(rng);
    o.u += du;
    o.v += pixel(rng);
    if (o.u_right >= 0.0) o.u_right += du;
  }
  test::perturbInitialState(&scene, 0.01, 0.003, 0.02, 9);
  BundleAdjustmentConfig config = tightConfig();
  config.linear_solver = BaLinearSolver::kSparseSchur;
  const BundleAdjustmentResult ceres = bundleAdjust(scene.problem, config);
  config.linear_solver = BaLinearSolver::kAuto;
  config.native_sparse = true;
  const BundleAdjustmentResult ours = bundleAdjust(scene.problem, config);
  ASSERT_TRUE(ours.success);
  EXPECT_EQ(ceres.linear_solver, "SPARSE_SCHUR");
  EXPECT_EQ(ours.linear_solver, "NATIVE_SPARSE_SCHUR");
  EXPECT_NEAR(ours.initial_cost, ceres.initial_cost, 1e-9 * ceres.initial_cost);
  EXPECT_NEAR(ours.final_chi2, ceres.final_chi2, 1e-7 * ceres.final_chi2);
  EXPECT_LT(ours.final_chi2, 0.1 * ours.initial_cost);  // the start was far: chi2 is the noise's now
  EXPECT_EQ(ours.outlier, ceres.outlier);
  double worst = 0.0;
  for (size_t k = 0; k < scene.T_C_G_true.size(); ++k) {
    worst = std::max(worst, test::poseDistance(ours.T_C_G[k], ceres.T_C_G[k]));
  }
  EXPECT_LT(worst, 1e-6);
  config.native_sparse = false;
  EXPECT_EQ(bundleAdjust(scene.problem, config).linear_solver, "SPARSE_SCHUR");
}

}  // namespace
}  // namespace cblox
